#include "engine/gcode/GcodeCodes.h"

#include <cmath>

namespace engage::gcode {

int codeOf(double value) {
  return static_cast<int>(std::lround(value * 10.0));
}
std::string codeName(char letter, int code) {
  std::string s(1, letter);
  s += std::to_string(code / 10);
  if (code % 10) s += "." + std::to_string(code % 10);
  return s;
}

int gGroup(int g) {
  switch (g) {
    case G_0:
    case G_1:
    case G_2:
    case G_3:
    case G_5:
    case G_5_1:
    case G_5_2:
    case G_5_3:
    case G_33:
    case G_33_1:
    case G_38_2:
    case G_38_3:
    case G_38_4:
    case G_38_5:
    case G_70:
    case G_71:
    case G_71_1:
    case G_71_2:
    case G_72:
    case G_72_1:
    case G_72_2:
    case G_73:
    case G_76:
    case G_80:
    case G_81:
    case G_82:
    case G_83:
    case G_84:
    case G_85:
    case G_86:
    case G_87:
    case G_88:
    case G_89:
      return 1;
    case G_17:
    case G_17_1:
    case G_18:
    case G_18_1:
    case G_19:
    case G_19_1:
      return 2;
    case G_90:
    case G_91:
      return 3;
    case G_90_1:
    case G_91_1:
      return 4;
    case G_93:
    case G_94:
    case G_95:
      return 5;
    case G_20:
    case G_21:
      return 6;
    case G_40:
    case G_41:
    case G_41_1:
    case G_42:
    case G_42_1:
      return 7;
    case G_43:
    case G_43_1:
    case G_43_2:
    case G_43_4:
    case G_43_5:
    case G_49:
    case G_234:
      return 8;
    case G_68_2:
    case G_69:
      return 16;
    case G_254:
    case G_255:
      return 23;
    case G_53_1:
      return 24;  // (non-modal, but it takes no axis words: not group 0)
    case G_98:
    case G_99:
      return 10;
    case G_54:
    case G_55:
    case G_56:
    case G_57:
    case G_58:
    case G_59:
    case G_59_1:
    case G_59_2:
    case G_59_3:
      return 12;
    case G_61:
    case G_61_1:
    case G_64:
      return 13;
    case G_96:
    case G_97:
      return 14;
    case G_7:
    case G_8:
      return 15;
    case G_4:
    case G_10:
    case G_28:
    case G_28_1:
    case G_30:
    case G_30_1:
    case G_53:
    case G_92:
    case G_92_1:
    case G_92_2:
    case G_92_3:
    case G_52:
      return 0;
    default:
      return -1;
  }
}

bool isLatheCycle(int g) {
  return g == G_70 || (g >= G_71 && g <= G_71_2) || (g >= G_72 && g <= G_72_2);
}

int mGroup(int m) {
  switch (m) {
    case M_0:
    case M_1:
    case M_2:
    case M_30:
    case M_60:
    case M_97:
    case M_98:
    case M_99:
      return 4;
    case M_6:
    case M_61:
      return 6;
    case M_3:
    case M_4:
    case M_5:
      return 7;
    case M_7:
    case M_8:
    case M_9:
      return 8;
    case M_48:
    case M_49:
    case M_50:
    case M_51:
    case M_52:
    case M_53:
      return 9;
    case M_62:
    case M_63:
    case M_64:
    case M_65:
    case M_66:
    case M_67:
    case M_68:
      return 5;
    case M_70:
    case M_71:
    case M_72:
    case M_73:
      return 10;
    default:
      return -1;
  }
}

}  // namespace engage::gcode

#pragma once
/// \file GcodeCodes.h
/// The G and M codes the interpreter knows, by name, with LinuxCNC's convention
/// (rs274ngc's enums): a code is its number times ten, so G38.2 is G_38_2 = 382 and M6 is
/// M_6 = 60. Also each code's modal group and its name for messages.

#include <string>

namespace engage::gcode {

/// G codes (number x 10).
enum GCode : int {
  G_0 = 0,
  G_1 = 10,
  G_2 = 20,
  G_3 = 30,
  G_4 = 40,
  G_5 = 50,
  G_5_1 = 51,
  G_5_2 = 52,
  G_5_3 = 53,
  G_7 = 70,
  G_8 = 80,
  G_10 = 100,
  G_17 = 170,
  G_17_1 = 171,
  G_18 = 180,
  G_18_1 = 181,
  G_19 = 190,
  G_19_1 = 191,
  G_20 = 200,
  G_21 = 210,
  G_28 = 280,
  G_28_1 = 281,
  G_30 = 300,
  G_30_1 = 301,
  G_33 = 330,
  G_33_1 = 331,
  G_38_2 = 382,
  G_38_3 = 383,
  G_38_4 = 384,
  G_38_5 = 385,
  G_40 = 400,
  G_41 = 410,
  G_41_1 = 411,
  G_42 = 420,
  G_42_1 = 421,
  G_43 = 430,
  G_43_1 = 431,
  G_43_2 = 432,
  G_43_4 = 434,  ///< Fanuc: tool centre point control on (with H, as G43)
  G_43_5 = 435,  ///< Fanuc: tool centre point control type 2 (the tool's axis as I, J, K)
  G_49 = 490,
  G_52 = 520,
  G_53 = 530,
  G_53_1 = 531,  ///< Fanuc: turn the rotary axes to the tilted work plane's Z
  G_54 = 540,
  G_55 = 550,
  G_56 = 560,
  G_57 = 570,
  G_58 = 580,
  G_59 = 590,
  G_59_1 = 591,
  G_59_2 = 592,
  G_59_3 = 593,
  G_61 = 610,
  G_61_1 = 611,
  G_64 = 640,
  G_65 = 650,    ///< Fanuc/Haas macro call: run by the interpreter's loop, not a modal group
  G_68_2 = 682,  ///< Fanuc: tilted work plane X Y Z (origin) I J K (Euler angles Z, X', Z'')
  G_69 = 690,
  G_70 = 700,
  G_71 = 710,
  G_71_1 = 711,
  G_71_2 = 712,
  G_72 = 720,
  G_72_1 = 721,
  G_72_2 = 722,
  G_73 = 730,
  G_76 = 760,
  G_80 = 800,
  G_81 = 810,
  G_82 = 820,
  G_83 = 830,
  G_84 = 840,
  G_85 = 850,
  G_86 = 860,
  G_87 = 870,
  G_88 = 880,
  G_89 = 890,
  G_90 = 900,
  G_90_1 = 901,
  G_91 = 910,
  G_91_1 = 911,
  G_92 = 920,
  G_92_1 = 921,
  G_92_2 = 922,
  G_92_3 = 923,
  G_93 = 930,
  G_94 = 940,
  G_95 = 950,
  G_96 = 960,
  G_97 = 970,
  G_98 = 980,
  G_99 = 990,
  G_234 = 2340,  ///< Haas: tool centre point control (TCPC, with H, as G43)
  G_254 = 2540,  ///< Haas: dynamic work offset (DWO)
  G_255 = 2550,  ///< Haas: DWO off
};

/// M codes (number x 10).
enum MCode : int {
  M_0 = 0,
  M_1 = 10,
  M_2 = 20,
  M_3 = 30,
  M_4 = 40,
  M_5 = 50,
  M_6 = 60,
  M_7 = 70,
  M_8 = 80,
  M_9 = 90,
  M_30 = 300,
  M_48 = 480,
  M_49 = 490,
  M_50 = 500,
  M_51 = 510,
  M_52 = 520,
  M_53 = 530,
  M_60 = 600,
  M_61 = 610,
  M_62 = 620,
  M_63 = 630,
  M_64 = 640,
  M_65 = 650,
  M_66 = 660,
  M_67 = 670,
  M_68 = 680,
  M_70 = 700,
  M_71 = 710,
  M_72 = 720,
  M_73 = 730,
  M_97 = 970,
  M_98 = 980,
  M_99 = 990,
};

/// A G or M word's number times ten, e.g. G5.2 -> 52, G90.1 -> 901.
int codeOf(double value);

/// The code's name for messages: codeName('G', 382) is "G38.2".
std::string codeName(char letter, int code);

/// The modal group of a G code (x10) as LinuxCNC numbers them, -1 for an unknown code.
int gGroup(int g);

/// G70, G71, G71.1, G71.2, G72, G72.1, G72.2 (x10).
bool isLatheCycle(int g);

/// The modal group of an M code (x10), -1 for an unknown code.
int mGroup(int m);

}  // namespace engage::gcode

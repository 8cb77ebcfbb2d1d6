#pragma once
/// \file Material.h
/// A workpiece material's cutting coefficients, as data (data/materials/*.json or a user's
/// file). Two force models, each with its source:
///
/// - the linear edge-force model of milling mechanics (Altintas, Manufacturing Automation,
///   ch. 2): on an edge element of width db cutting a chip of thickness h,
///   dF_t = (K_tc h + K_te) db, dF_r = (K_rc h + K_re) db, dF_a = (K_ac h + K_ae) db;
///   K_.c in N/mm^2, K_.e in N/mm. Fitted per material and tool from slot tests.
/// - Kienzle's: dF_t = k_c1.1 h^(1 - m_c) db (k_c1.1 in N/mm^2 at h = 1 mm), with optional
///   k_f1.1, m_f (radial) and k_p1.1, m_p (axial); what material data sheets, tool makers'
///   catalogues and FreeCAD's material cards give. Without the radial and axial pairs only
///   the tangential force, torque and power are modelled.
///
/// File format (JSON; numbers in the units named above):
///   {"name": "...", "model": "linear" | "kienzle",
///    "linear": {"Ktc":..,"Krc":..,"Kac":..,"Kte":..,"Kre":..,"Kae":..,
///               "source": "...", "conditions": "..."},
///    "kienzle": {"kc11":..,"mc":.., "kf11":..,"mf":.., "kp11":..,"mp":..,
///                "source": "...", "conditions": "..."}}
/// "model" picks one when both are given (default: linear). Every model needs a "source".

#include <string>
#include <vector>

namespace engage {

enum class ForceModel { Linear, Kienzle };

/// Linear edge-force coefficients: cutting N/mm^2, edge N/mm.
struct LinearCoefficients {
  double Ktc = 0, Krc = 0, Kac = 0;
  double Kte = 0, Kre = 0, Kae = 0;
};

/// Kienzle coefficients: k N/mm^2 at a 1 mm chip, exponents m (force ~ h^(1 - m)).
struct KienzleCoefficients {
  double kc11 = 0, mc = 0;
  double kf11 = 0, mf = 0;  ///< radial; 0: not modelled
  double kp11 = 0, mp = 0;  ///< axial; 0: not modelled
};

struct Material {
  std::string name;
  std::string path;  ///< the file it was read from
  ForceModel model = ForceModel::Linear;
  LinearCoefficients linear;
  KienzleCoefficients kienzle;
  std::string source;      ///< the citation of the model in use
  std::string conditions;  ///< the tool and conditions it was measured with
  /// The force grows with the chip thickness as h^exponent (1 linear; 1 - m_c Kienzle).
  double exponent() const { return model == ForceModel::Linear ? 1.0 : 1.0 - kienzle.mc; }
};

/// The bundled materials' folder (data/materials of the source tree).
std::string materialFolder();

/// The names of the bundled materials (their file names without .json), sorted.
std::vector<std::string> bundledMaterials();

/// Whether `nameOrPath` names a file (it has a / or ends in .json) rather than a bundled
/// material.
bool materialIsFile(const std::string& nameOrPath);

/// The file of `nameOrPath`: itself when it names a file, else the bundled material's file
/// (which may not exist).
std::string materialFile(const std::string& nameOrPath);

/// Read `nameOrPath`: a file (any name with a / or ending in .json), else a bundled
/// material's name. `model` "" keeps the file's choice, "linear" or "kienzle" forces one.
/// Throws ParameterError naming the file and the field: an unknown name (listing the
/// bundled ones), unreadable JSON, a missing or non-positive coefficient, an exponent outside
/// [0, 1), a model without a source.
Material readMaterial(const std::string& nameOrPath, const std::string& model = "");

}  // namespace engage

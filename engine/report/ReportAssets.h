#pragma once
/// \file ReportAssets.h
/// The files report.html inlines, built into the program so that a report needs nothing at
/// run time and opens from disk with no network: three.js with its OrbitControls (Debian
/// libjs-three) and dygraphs (libjs-dygraphs), found when CMake configures, and engage's own
/// report.js and report.css beside this header.

#include <string>

namespace engage {

/// The text of one of "three.min.js", "OrbitControls.js", "dygraph.min.js", "dygraph.min.css",
/// "report.js", "report.css". Throws Error for another name.
const std::string& reportAsset(const std::string& name);

}  // namespace engage

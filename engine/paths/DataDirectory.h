#pragma once
/// \file DataDirectory.h
/// Where engage's bundled data is (materials, the paper's boundaries and programs, example
/// tools and machines): found at run time, so that an installed engage (`cmake --install`) and
/// its Python module work with the source tree moved away.

#include <string>

namespace engage {

/// The data folder, the first of: $ENGAGE_DATA if set; share/engage/data beside the program
/// or the Python module that runs this code (prefix/bin/engage: prefix/share/engage/data;
/// prefix/lib/python3/dist-packages/engage.so: the same prefix); the source tree's data/
/// this build was made from. A folder counts only if it holds materials/. Throws Error when
/// none does, naming the places looked at.
std::string dataDirectory();

}  // namespace engage

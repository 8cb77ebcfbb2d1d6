#pragma once
// Closed part meshes with known geometry for the --part tests (tests/stock/Part.cpp,
// tests/engine/run/PartCheck.cpp): a block, and a block with a slot along X, as triangle meshes
// and as OBJ text.

#include "stock/TriangleMesh.h"

#include <array>
#include <string>
#include <vector>

namespace engage::test {

/// A prism along X from x0 to x1 over a polygon in the YZ plane (counter-clockwise seen from
/// +X) whose end caps are the given triangles of its corners (counter-clockwise seen from +X).
inline TriangleMesh prismAlongX(double x0, double x1, const std::vector<std::array<double, 2>>& yz,
                                const std::vector<std::array<unsigned, 3>>& cap) {
  TriangleMesh m;
  const auto n = static_cast<unsigned>(yz.size());
  for (double x : {x0, x1})
    for (const auto& p : yz)
      m.points.push_back(
          {static_cast<float>(x), static_cast<float>(p[0]), static_cast<float>(p[1])});
  for (const auto& t : cap) {
    m.triangles.push_back({t[0], t[2], t[1]});              // the x0 cap faces -X
    m.triangles.push_back({n + t[0], n + t[1], n + t[2]});  // the x1 cap faces +X
  }
  for (unsigned k = 0; k < n; ++k) {
    const unsigned j = (k + 1) % n;
    m.triangles.push_back({k, j, n + j});
    m.triangles.push_back({k, n + j, n + k});
  }
  return m;
}

/// The block [x0, x1] x [y0, y1] x [z0, z1].
inline TriangleMesh block(double x0, double y0, double z0, double x1, double y1, double z1) {
  return prismAlongX(x0, x1, {{y0, z0}, {y1, z0}, {y1, z1}, {y0, z1}}, {{0, 1, 2}, {0, 2, 3}});
}

/// The block with a slot along X through it: y in [b0, b1], from the top z1 down to `floor`.
inline TriangleMesh slottedBlock(double x0, double y0, double z0, double x1, double y1, double z1,
                                 double b0, double b1, double floor) {
  // The U's corners: A B C D E F G H; its six triangles lie in the bar below the floor and in
  // the two posts.
  return prismAlongX(
      x0, x1,
      {{y0, z0}, {y1, z0}, {y1, z1}, {b1, z1}, {b1, floor}, {b0, floor}, {b0, z1}, {y0, z1}},
      {{0, 1, 4}, {0, 4, 5}, {1, 2, 3}, {1, 3, 4}, {0, 5, 6}, {0, 6, 7}});
}

/// The mesh as OBJ text.
inline std::string objText(const TriangleMesh& m) {
  std::string s;
  char line[128];
  for (const auto& p : m.points) {
    std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", p[0], p[1], p[2]);
    s += line;
  }
  for (const auto& t : m.triangles)
    s += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
         std::to_string(t[2] + 1) + "\n";
  return s;
}

}  // namespace engage::test

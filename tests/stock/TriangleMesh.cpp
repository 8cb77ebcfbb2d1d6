// Tests of stock/TriangleMesh.h: a broken mesh is refused with its actual problem in one line.

#include "stock/TriangleMesh.h"

#include "cutters/Error.h"

#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

using namespace engage;
using Catch::Matchers::Contains;

namespace {

/// A binary STL of the unit tetrahedron's four faces; `count` overrides the header's count,
/// `bad` puts that value into the first coordinate.
std::string tetrahedronStl(std::uint32_t count = 4, float bad = 0.0f) {
  const std::array<std::array<float, 3>, 4> p = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::string s(80, ' ');
  s.append(reinterpret_cast<const char*>(&count), 4);
  for (const auto& f : faces) {
    float rec[12] = {};
    for (int v = 0; v < 3; ++v)
      for (int a = 0; a < 3; ++a)
        rec[3 + 3 * v + a] = p[static_cast<std::size_t>(f[v])][static_cast<std::size_t>(a)];
    s.append(reinterpret_cast<const char*>(rec), sizeof rec);
    s.append(2, '\0');
  }
  if (bad != 0.0f || std::isnan(bad)) std::memcpy(&s[84 + 12], &bad, 4);
  return s;
}

std::string write(const std::string& name, const std::string& bytes) {
  const auto path = std::filesystem::temp_directory_path() / ("engage_mesh_" + name);
  std::ofstream(path, std::ios::binary) << bytes;
  return path.string();
}

}  // namespace

TEST_CASE("a sound binary STL reads, a broken one names its problem", "[stock]") {
  const TriangleMesh m = readMesh(write("good.stl", tetrahedronStl()));
  CHECK(m.triangles.size() == 4);
  CHECK(boundaryEdgeCount(m) == 0);
  CHECK_THROWS_WITH(readMesh(write("count.stl", tetrahedronStl(5))),
                    Contains("its header counts 5 triangles, which take 334 bytes, but the file "
                             "has 284"));
  CHECK_THROWS_WITH(
      readMesh(write("nan.stl", tetrahedronStl(4, std::numeric_limits<float>::quiet_NaN()))),
      Contains("triangle 1 has a NaN coordinate"));
  CHECK_THROWS_WITH(
      readMesh(write("inf.stl", tetrahedronStl(4, std::numeric_limits<float>::infinity()))),
      Contains("triangle 1 has an infinite coordinate"));
  CHECK_THROWS_WITH(readMesh(write("short.stl", "solid x")),
                    Contains("too short for a binary STL (7 bytes, at least 84)"));
  // A face naming no vertex made Debian's OpenMesh abort on an assertion (found by fuzzing).
  CHECK_THROWS_WITH(readMesh(write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")),
                    Contains("line 4: face vertex '9' is not one of the 3 vertices before it"));
  CHECK_THROWS_WITH(readMesh(write("empty.obj", "v 0 0 0\nf /0\n")),
                    Contains("line 2: face vertex '/0'"));
  CHECK(readMesh(write("good.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/2 -1\n")).triangles.size() ==
        1);
}

TEST_CASE("writeStl writes every triangle with its normal, where the mesh is not a manifold",
          "[stock]") {
  // Three triangles on one edge (x from 0 to 1): a marching-cubes mesh has such edges where two
  // cuts meet in one cell, and a halfedge mesh refuses the third face. The file is a header,
  // the count, and per triangle the unit normal, three corners and two zero bytes.
  TriangleMesh m;
  m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, -1, 0}};
  m.triangles = {{0, 1, 2}, {0, 3, 1}, {1, 0, 4}};
  const std::string path =
      (std::filesystem::temp_directory_path() / "engage_mesh_fan.stl").string();
  writeStl(m, path);
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  REQUIRE(bytes.size() == 84 + 3 * 50);
  std::uint32_t count = 0;
  std::memcpy(&count, bytes.data() + 80, 4);
  CHECK(count == 3);
  // The normals by hand: (1,0,0) x (0,1,0) = +z; (0,0,1) x (1,0,0) = +y; for 1,0,4: (-1,0,0) x
  // (-1,-1,0) = (0,0,1).
  const float normals[3][3] = {{0, 0, 1}, {0, 1, 0}, {0, 0, 1}};
  for (std::size_t t = 0; t < 3; ++t) {
    float rec[12];
    std::memcpy(rec, bytes.data() + 84 + 50 * t, sizeof rec);
    for (std::size_t a = 0; a < 3; ++a) {
      CHECK(rec[a] == normals[t][a]);
      for (std::size_t v = 0; v < 3; ++v)
        CHECK(rec[3 + 3 * v + a] == m.points[m.triangles[t][v]][a]);
    }
  }
  std::filesystem::remove(path);
}

TEST_CASE("open edges: each edge that one triangle alone uses", "[stock]") {
  // A tetrahedron (4 faces, 6 edges each used twice): closed. Without one face its 3 edges
  // are open; two such tetrahedra sharing nothing: 6; a fan of three triangles on one edge
  // (used 3 times, not open) around the same two vertices: 6 open rim edges.
  TriangleMesh m;
  m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  CHECK(boundaryEdgeCount(m) == 0);
  m.triangles.pop_back();
  CHECK(boundaryEdgeCount(m) == 3);
  TriangleMesh two = m;
  for (auto p : m.points)
    two.points.push_back({p[0] + 5.0f, p[1], p[2]});
  for (auto t : m.triangles)
    two.triangles.push_back({t[0] + 4, t[1] + 4, t[2] + 4});
  CHECK(boundaryEdgeCount(two) == 6);
  TriangleMesh fan;
  fan.points = {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}};
  fan.triangles = {{0, 1, 2}, {0, 1, 3}, {0, 1, 4}};
  CHECK(boundaryEdgeCount(fan) == 6);
}

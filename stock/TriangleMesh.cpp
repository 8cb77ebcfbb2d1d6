#include "stock/TriangleMesh.h"

#include "cutters/Error.h"
#include "stock/AtomicFile.h"

// OpenMesh's IO must be included before its mesh headers (its readers and writers register
// there).
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

namespace engage {
namespace {
using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;
}

namespace {

/// A binary STL checked before OpenMesh reads it (which takes a wrong triangle count or a NaN
/// silently): the size its header's count implies, and every coordinate finite. Returns the
/// problem in one line, or "" when it is sound. An ASCII STL ("solid" and "facet") is left to
/// the reader and the checks after it.
std::string binaryStlProblem(const std::string& bytes) {
  const bool ascii =
      bytes.compare(0, 5, "solid") == 0 && bytes.find("facet", 5) != std::string::npos;
  if (ascii) return "";
  if (bytes.size() < 84)
    return "too short for a binary STL (" + std::to_string(bytes.size()) + " bytes, at least 84)";
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 80, 4);
  const std::uint64_t expected = 84 + 50 * static_cast<std::uint64_t>(n);
  if (expected != bytes.size())
    return "its header counts " + std::to_string(n) + " triangles, which take " +
           std::to_string(expected) + " bytes, but the file has " + std::to_string(bytes.size());
  for (std::uint32_t t = 0; t < n; ++t)
    for (int k = 0; k < 9; ++k) {
      float v = 0.0f;
      std::memcpy(&v, bytes.data() + 84 + 50 * static_cast<std::size_t>(t) + 12 + 4 * k, 4);
      if (!std::isfinite(v))
        return "triangle " + std::to_string(t + 1) + " has " +
               (std::isnan(v) ? "a NaN" : "an infinite") + " coordinate";
    }
  return "";
}

/// An OBJ checked before OpenMesh reads it: Debian's OpenMesh aborts on an assertion when a
/// face line names no valid vertex (found by fuzzing). Every "f" line must name at least three
/// vertices by indices within the vertices read so far (negative: counted back). Returns the
/// problem with its line, or "".
std::string objProblem(const std::string& bytes) {
  std::istringstream in(bytes);
  long vertices = 0;
  int lineNumber = 0;
  for (std::string line; std::getline(in, line);) {
    ++lineNumber;
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "v") ++vertices;
    if (key != "f") continue;
    int count = 0;
    for (std::string ref; words >> ref; ++count) {
      char* end = nullptr;
      const long i = std::strtol(ref.c_str(), &end, 10);
      const bool number = end != ref.c_str() && (*end == '\0' || *end == '/');
      if (!number || i == 0 || i > vertices || -i > vertices)
        return "line " + std::to_string(lineNumber) + ": face vertex '" + ref +
               "' is not one of the " + std::to_string(vertices) + " vertices before it";
    }
    if (count < 3)
      return "line " + std::to_string(lineNumber) + ": a face of " + std::to_string(count) +
             " vertices (at least 3)";
  }
  return "";
}

}  // namespace

TriangleMesh readMesh(const std::string& path) {
  if (!std::filesystem::is_regular_file(path))
    throw Error("cannot read stock mesh '" + path + "': no such file");
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".stl" || ext == ".obj") {
    std::ifstream in(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string problem = ext == ".stl" ? binaryStlProblem(bytes) : objProblem(bytes);
    if (!problem.empty()) throw Error("cannot read stock mesh '" + path + "': " + problem);
  }
  omlog().disable();  // OpenMesh reports to the terminal; the one line below says what failed
  omerr().disable();
  Mesh mesh;
  const bool read = OpenMesh::IO::read_mesh(mesh, path);
  omerr().enable();
  if (!read) throw Error("cannot read stock mesh '" + path + "': not an STL, OBJ, OFF or PLY mesh");
  TriangleMesh out;
  for (const auto& v : mesh.vertices()) {
    const auto p = mesh.point(v);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      throw Error("cannot read stock mesh '" + path + "': vertex " + std::to_string(v.idx() + 1) +
                  " has a NaN or infinite coordinate");
    out.points.push_back({p[0], p[1], p[2]});
  }
  for (const auto& f : mesh.faces()) {
    std::vector<unsigned> idx;
    for (const auto& v : mesh.fv_range(f))
      idx.push_back(static_cast<unsigned>(v.idx()));
    for (std::size_t k = 1; k + 1 < idx.size(); ++k)
      out.triangles.push_back({idx[0], idx[k], idx[k + 1]});
  }
  return out;
}

std::size_t boundaryEdgeCount(const TriangleMesh& mesh) {
  // A closed (watertight) mesh uses each undirected edge exactly twice. The edges bucketed by
  // their smaller vertex (a counting sort), each vertex's few other ends then sorted and
  // counted, which is cheaper than sorting all edges as pairs.
  std::size_t vertices = 0;
  for (const auto& t : mesh.triangles)
    for (unsigned v : t)
      vertices = std::max<std::size_t>(vertices, std::size_t{v} + 1);
  std::vector<std::size_t> start(vertices + 1, 0);
  for (const auto& t : mesh.triangles)
    for (std::size_t k = 0; k < 3; ++k)
      ++start[std::min(t[k], t[(k + 1) % 3]) + 1u];
  for (std::size_t v = 0; v < vertices; ++v)
    start[v + 1] += start[v];
  std::vector<std::uint32_t> other(start.back());
  std::vector<std::size_t> next(start.begin(), start.end() - 1);
  for (const auto& t : mesh.triangles)
    for (std::size_t k = 0; k < 3; ++k) {
      const unsigned a = t[k], b = t[(k + 1) % 3];
      other[next[std::min(a, b)]++] = std::max(a, b);
    }
  std::size_t open = 0;
  for (std::size_t v = 0; v < vertices; ++v) {
    const auto first = other.begin() + start[v], last = other.begin() + start[v + 1];
    std::sort(first, last);
    for (auto i = first; i != last;) {
      auto j = i;
      while (j != last && *j == *i)
        ++j;
      if (j - i == 1) ++open;
      i = j;
    }
  }
  return open;
}

void writeStl(const TriangleMesh& m, const std::string& path) {
  // Written here, not through OpenMesh: its writer takes a halfedge mesh, which refuses a
  // face on an edge that two faces already have (a marching-cubes surface has such edges where
  // two cuts meet in one cell: the face would go missing from stock.stl without a word), and
  // building that mesh costs more than writing the triangles.
  const auto count = static_cast<std::uint32_t>(m.triangles.size());
  if (count != m.triangles.size())
    throw Error("cannot write '" + path + "': " + std::to_string(m.triangles.size()) +
                " triangles, more than a binary STL holds");
  writeFileAtomically(path, [&](std::ostream& os) {
    std::string header = "binary STL of engage's stock, mm";
    header.resize(80, ' ');
    os.write(header.data(), 80);
    os.write(reinterpret_cast<const char*>(&count), 4);
    std::vector<char> buffer;
    buffer.reserve(50 * 4096);
    auto flush = [&] {
      os.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      buffer.clear();
    };
    for (const auto& t : m.triangles) {
      const auto& p = m.points[t[0]];
      const auto& q = m.points[t[1]];
      const auto& r = m.points[t[2]];
      const double u[3] = {double(q[0]) - p[0], double(q[1]) - p[1], double(q[2]) - p[2]};
      const double v[3] = {double(r[0]) - p[0], double(r[1]) - p[1], double(r[2]) - p[2]};
      double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                     u[0] * v[1] - u[1] * v[0]};
      const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      float record[12];
      for (std::size_t a = 0; a < 3; ++a) {
        record[a] = length > 0.0 ? static_cast<float>(n[a] / length) : 0.0f;
        record[3 + a] = p[a];
        record[6 + a] = q[a];
        record[9 + a] = r[a];
      }
      const char* bytes = reinterpret_cast<const char*>(record);
      buffer.insert(buffer.end(), bytes, bytes + sizeof record);
      buffer.push_back('\0');
      buffer.push_back('\0');
      if (buffer.size() >= 50 * 4096) flush();
    }
    flush();
  });
}

}  // namespace engage

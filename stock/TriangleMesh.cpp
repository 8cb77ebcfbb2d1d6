#include "stock/TriangleMesh.h"

#include "cutters/Error.h"

// OpenMesh's IO must be included before its mesh headers (its readers and writers register
// there).
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <filesystem>
#include <map>
#include <utility>

namespace engage {
namespace {
using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;
}

TriangleMesh readMesh(const std::string& path) {
  if (!std::filesystem::is_regular_file(path))
    throw Error("cannot read stock mesh '" + path + "': no such file");
  Mesh mesh;
  if (!OpenMesh::IO::read_mesh(mesh, path))
    throw Error("cannot read stock mesh '" + path + "': not an STL, OBJ, OFF or PLY mesh");
  TriangleMesh out;
  for (const auto& v : mesh.vertices()) {
    const auto p = mesh.point(v);
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
  // Count undirected edges by use; a closed (watertight) mesh uses each exactly twice.
  std::map<std::pair<unsigned, unsigned>, int> uses;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const unsigned a = t[static_cast<std::size_t>(k)];
      const unsigned b = t[static_cast<std::size_t>((k + 1) % 3)];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  std::size_t open = 0;
  for (const auto& [edge, n] : uses)
    if (n == 1) ++open;
  return open;
}

void writeStl(const TriangleMesh& m, const std::string& path) {
  omlog().disable();  // OpenMesh's writers report to the terminal; a library stays silent
  omout().disable();
  Mesh mesh;
  std::vector<Mesh::VertexHandle> vh;
  vh.reserve(m.points.size());
  for (const auto& p : m.points)
    vh.push_back(mesh.add_vertex(Mesh::Point(p[0], p[1], p[2])));
  for (const auto& t : m.triangles)
    mesh.add_face(vh[t[0]], vh[t[1]], vh[t[2]]);
  mesh.request_face_normals();
  mesh.update_face_normals();
  const std::string tmp = path + ".part.stl";
  OpenMesh::IO::Options options(OpenMesh::IO::Options::Binary);
  if (!OpenMesh::IO::write_mesh(mesh, tmp, options)) throw Error("cannot write '" + path + "'");
  std::filesystem::rename(tmp, path);
}

}  // namespace engage

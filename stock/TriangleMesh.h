#pragma once
/// \file TriangleMesh.h
/// Triangle meshes in and out: reading stock models (STL, OBJ, OFF, PLY; OpenMesh behind this
/// header) and writing binary STL (directly: OpenMesh's writer drops faces, TriangleMesh.cpp).

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace engage {

/// Vertices (mm) and triangles (vertex indices, counter-clockwise seen from outside).
struct TriangleMesh {
  std::vector<std::array<float, 3>> points;
  std::vector<std::array<unsigned, 3>> triangles;
};

/// Read a mesh; polygons are fanned into triangles. Throws Error when the file is missing
/// or unreadable.
TriangleMesh readMesh(const std::string& path);

/// Number of edges that belong to one triangle only (0 for a closed mesh).
std::size_t boundaryEdgeCount(const TriangleMesh& mesh);

/// Write binary STL to a temporary name and rename it to `path` when complete. Throws Error.
void writeStl(const TriangleMesh& mesh, const std::string& path);

}  // namespace engage

#pragma once
/// \file DexelMesh.h
/// A dexel stock's surface as a triangle mesh straight from its rays, where the stock is a
/// heightfield over its box, as a 3-axis program leaves it: every column holds material from
/// the box's floor up, none of it over air (more than half a cell's height of material above
/// a gap is an overhang; slivers a cut left over a gap count). A column's height is its material
/// over the floor as a mean height (each interval's length times its share of the column; the box's
/// last row and column by their share of the box), so a wall crossing a column stands between two
/// rays where the column's share puts it, and the mesh encloses the stock's volume. The top's
/// vertices are the rays' heights at their positions (the box's rim rays on its faces); square
/// blocks of the ray lattice whose heights lie within a tolerance of one plane are merged bottom up
/// (a quadtree, 2 x 2 blocks into one), each block a fan around its centre through every lattice
/// vertex on its edges that a neighbour uses, so that the mesh is closed without T-junctions; then
/// the box's four walls and its floor. Meshing takes about 0.08 us a ray (0.23 s for 3 million),
/// where meshing the stock's voxel fractions (VoxelStock::viewMesh) takes 2 us a partial voxel
/// (14.6 s for the 7.3 million of the same stock).

#include "stock/TriangleMesh.h"

#include <cstddef>
#include <optional>
#include <vector>

namespace engage {

class DexelStock;

/// The surface of `stock` within about `maxTriangles` triangles: blocks merged within a tenth
/// of the vertices' spacing of a plane, and where that is not enough, every second, fourth, ...
/// ray a vertex (each the mean height of the rays around it). `maxTriangles` 0: every ray a
/// vertex, only blocks exactly planar (to 1e-9 mm) merged. `cellSize`, when given, receives the
/// vertices' spacing (mm). nullopt where the stock is not such a heightfield (a column empty
/// or cut through, an overhang, a floor that is not flat, fewer than 2 rays a side): mesh its
/// voxels instead.
std::optional<TriangleMesh> heightfieldMesh(const DexelStock& stock, std::size_t maxTriangles,
                                            double* cellSize = nullptr);

/// heightfieldMesh for several budgets at once (the rays' heights and each spacing's blocks
/// made once for all): the n-th mesh within about budgets[n] triangles, its spacing in
/// (*cellSizes)[n].
std::optional<std::vector<TriangleMesh>> heightfieldMeshes(
    const DexelStock& stock, const std::vector<std::size_t>& budgets,
    std::vector<double>* cellSizes = nullptr);

}  // namespace engage

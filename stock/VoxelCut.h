#pragma once
/// \file VoxelCut.h
/// The cut of one voxel of the voxel stock by a step's swept solid (private to stock/): the
/// material fraction the voxel keeps, and the planes it keeps (VoxelPlanes.h). How the cut's
/// surface is found in a voxel, and what was measured for each choice, is in the header of
/// VoxelStock.cpp and in docs/voxel-stock.md.

#include "cutters/Sweep.h"
#include "stock/VoxelPlanes.h"

#include <Eigen/Core>

#include <cstdint>

namespace engage::voxel {

/// The material fraction left in the voxel at p (size h) that held `before` once the swept
/// solid is removed; updates the voxel's planes. `serial` numbers this removal.
///
/// The swept solid in the voxel is the half-space of the tangent plane of its signed
/// distance, or near a sharp edge of the cutter (a flat bottom's rim) the wedge between the
/// two faces (Sweep::localFaces), and it takes its exact share of the material (polyhedral
/// clipping, stock/CubeClip.h); near a flat bottom's rim on a step that changes height,
/// sub-cube by sub-cube (rimRemaining()). A voxel that is all material keeps the rest and, as one
/// plane, the cut's boundary. A partial voxel holds the material between up to two earlier
/// planes (a stock face, the previous pass's wall, the last cut): the cut takes the share of
/// that material inside it, and the voxel keeps the cut's plane and the earlier plane that
/// bounds the rest more tightly. Where two surfaces cross one voxel (the front of a side cut
/// meeting the previous pass's wall, a helix turn meeting the last turn's floor) a fraction
/// alone cannot say how much of the material the cut reaches: min(before, 1 - cut) assumed
/// all or none of it, which cost 0.8 % per step on a side cut and 2 % on a helix at
/// D / h = 20 (docs/accuracy.md).
double remaining(const Sweep& sweep, const Eigen::Vector3d& p, double h, double before,
                 LeafPlanes& planes, std::uint32_t offset, int serial, const Box3* box,
                 std::uint64_t sweepId);

}  // namespace engage::voxel

#pragma once
/// \file Stock.h
/// The material as the simulation sees it: any stock model that can remove a step's swept
/// cutter and say what it removed. Two models implement it, computed in unrelated ways, so
/// that where they agree a user can trust the number: VoxelStock (volume fractions on
/// OpenVDB) and DexelStock (vertical rays holding material intervals).

#include "cutters/AptCutter.h"
#include "cutters/Sweep.h"

#include <Eigen/Core>

#include <cstddef>
#include <utility>
#include <vector>

namespace engage {

/// What one removal did: measured volume and engagement, and the work it cost.
struct Removal {
  double volume = 0.0;         ///< removed volume, mm^3
  double axialDepth = 0.0;     ///< extent of the removed material along the tool axis, mm
  double radialWidth = 0.0;    ///< extent across the feed direction (at the step end), mm
  double top = 0.0;            ///< height of the removed material's top above the tip, mm
  double engagementRad = 0.0;  ///< angle of the cutter's periphery in contact, rad
  /// Volume-weighted mean offset of the removed material across the feed direction, mm:
  /// + on the left of the direction of travel (seen from +Z). Tells which side the stock is.
  double lateral = 0.0;
  long voxelsChanged = 0;  ///< cells (voxels, or rays of a dexel stock) that lost material
  long voxelsVisited = 0;  ///< cells whose distance was evaluated
  /// For each of the step's parts (StepCut::parts), the material inside its slim and its full
  /// swept solid after the removal, mm^3 (Stock::materialInside); the full one 0 where the
  /// slim one is within the part's threshold and the model did not need it.
  std::vector<std::pair<double, double>> partsMet;
};

/// A part of the tool that must cut nothing (a shank, a holder) over one step, asked after
/// the step's removal for the material inside it below `top`: first the part a cell slimmer
/// (`slim`), and where that meets more than `threshold` mm^3, the part itself (`full`).
struct PartSweep {
  const Sweep* slim = nullptr;
  const Sweep* full = nullptr;
  double top = 0.0;
  double threshold = 0.0;
};

/// One step for Stock::removeSteps: its swept solid (alive until the call returns; none for a
/// step known to reach no material, whose parts alone are asked), the step's number and
/// duration (as remove takes them).
struct StepCut {
  const Sweep* sweep = nullptr;
  int step = 0;
  double dtSeconds = 0.0;
  std::vector<PartSweep> parts;  ///< what is asked after the step's removal
};

/// A stock model.
class Stock {
 public:
  virtual ~Stock() = default;
  /// Its resolution, mm: the voxel size, or the ray spacing.
  virtual double resolution() const = 0;
  /// Material volume, mm^3.
  virtual double volume() const = 0;
  /// Bounds of the material, mm.
  virtual Box3 bounds() const = 0;
  /// Bytes the model holds.
  virtual std::size_t memoryBytes() const = 0;
  /// The material inside a swept solid below the height `top`, mm^3, without removing it
  /// (what a shank or a holder meets): the fractions of the voxels, or the pieces of rays a
  /// resolution long, whose centres lie inside. Accurate to about a layer of cells on the
  /// contact's surface.
  virtual double materialInside(const Sweep& sweep, double top) const = 0;
  /// The material's share at each point, 0 to 1, interpolated between cells (trilinearly
  /// between voxel centres; bilinearly between rays, each in or out at the point's height):
  /// about 0.5 on the material's surface. Read after a removal, just outside the cutter, it
  /// tells which part of the edge is in contact (engine/physics/Engagement.h).
  virtual std::vector<double> materialAt(const std::vector<Eigen::Vector3d>& points) const = 0;
  /// Remove one step's swept solid; `step` and `dtSeconds` label it (for capture grids).
  virtual Removal remove(const Sweep& sweep, int step = 0, double dtSeconds = 0.0) = 0;
  /// Remove consecutive steps in their order, each step's parts asked after its removal,
  /// nothing else read from the stock between them: the removals remove() and materialInside
  /// would give one after another. A model may take them together (the dexel stock: tiles of
  /// columns side by side, each applying the steps that reach it).
  virtual std::vector<Removal> removeSteps(const std::vector<StepCut>& steps) {
    std::vector<Removal> out;
    out.reserve(steps.size());
    for (const StepCut& s : steps) {
      out.push_back(s.sweep ? remove(*s.sweep, s.step, s.dtSeconds) : Removal{});
      for (const PartSweep& part : s.parts) {
        const double slim = materialInside(*part.slim, part.top);
        out.back().partsMet.emplace_back(
            slim, slim > part.threshold ? materialInside(*part.full, part.top) : 0.0);
      }
    }
    return out;
  }
};

}  // namespace engage

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
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace engage {

/// What one removal did: measured volume and engagement, and the work it cost.
struct Removal {
  double volume = 0.0;      ///< removed volume, mm^3
  double axialDepth = 0.0;  ///< extent of the removed material along the tool axis, mm
  double top = 0.0;         ///< height of the removed material's top above the tip, mm
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

/// Whether points lie in material, read to a fraction of a cell: a cell crossed by the
/// material's surface holds it as planes that leave the cell's share of material (the voxel
/// stock's stored planes; a dexel column's share as a line across it, its slope from the
/// neighbours' shares, and its intervals exact along z). Exact for plane faces and the cuts'
/// walls away from corners; within a cell where two faces meet, to about a tenth of a cell.
/// Read just outside the cutter after a removal, it tells which part of the edge is in
/// contact (engine/physics/Engagement.h). A reader keeps what it worked out about the cells it
/// read for the points it is asked next.
class MaterialReader {
 public:
  virtual ~MaterialReader() = default;
  /// 1 where the point lies in material, 0 where not; valid until the next call.
  virtual const std::vector<std::uint8_t>& read(const std::vector<Eigen::Vector3d>& points) = 0;
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
  /// Reads whether points lie in material (MaterialReader), for as long as the stock does not
  /// change: one reader for one measurement of a step's contact. `afterStep`: the material as
  /// it was after that step (an index into the last removeSteps call) where
  /// readsWithinBatch(); kLatest, as it is now.
  static constexpr std::size_t kLatest = static_cast<std::size_t>(-1);
  virtual std::unique_ptr<MaterialReader> materialReader(std::size_t afterStep = kLatest) const = 0;
  /// Whether materialReader can read the material as it was after each step of the last
  /// removeSteps call (else only as it is now: a caller that reads the stock after each step
  /// then removes them one at a time).
  virtual bool readsWithinBatch() const { return false; }
  /// Whether remove() takes a tilted tool's sweep (StepPath::tilted: a 4- or 5-axis step).
  virtual bool followsTiltedTools() const { return false; }
  /// How far from a point (in cells) a second surface may change a MaterialReader's reading of
  /// the first: beyond it, a wall is read exactly whatever else was cut nearby.
  virtual double readingReach() const = 0;
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

#pragma once
/// \file Part.h
/// The part a program was made for (--part), and how far a stock is from it. The part is a
/// closed triangle mesh (STL, OBJ, OFF, PLY) or the zero surface of a .vdb level set, in mm, in
/// the program's frame. Its surface is cut into samples no wider than a spacing; from each
/// sample, along the part's outward normal, the stock's surface is found to a fraction of a
/// cell (Stock::materialReader: the dexel intervals and lines, the voxel planes), up to the
/// part's medial axis (where another point of the part is nearer than the sample). That
/// distance, signed, is the deviation: material left over the part (> 0), or the part's
/// material gone (< 0, a gouge). The samples' shares partition the space near the part among
/// its faces, so area x deviation summed over samples is the volume between the two surfaces,
/// and a deviation is the distance of the stock's surface from the part, never more.
/// CGAL (closest points, inside tests) is behind this header; the .vdb files in PartFiles.cpp.

#include "stock/Stock.h"
#include "stock/TriangleMesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace engage {

/// A piece of the part's surface: its centre, outward unit normal and area (mm, mm^2), and
/// its corners (to be split further).
struct PartSample {
  Eigen::Vector3f point;
  Eigen::Vector3f normal;
  float area = 0.0f;
  std::array<Eigen::Vector3f, 3> corners;
};

/// The pieces of a sample no longer than `spacing` across, split as Part::samples splits.
std::vector<PartSample> splitSample(const PartSample& sample, double spacing);

/// The stock against the part at one sample.
struct SampleDeviation {
  /// mm along the normal from the sample to the stock's surface, cut at the part's medial
  /// axis (where another point of the part is nearer than the sample): > 0 material left over
  /// the part, < 0 the part's material gone (a gouge). Within the share, the distance of the
  /// stock's surface from the part; area x deviation is the sample's share of the volume
  /// between the two surfaces.
  float deviation = 0.0f;
  /// Where the stock's surface was met (else where the walk ended), mm.
  Eigen::Vector3f stockPoint{0.0f, 0.0f, 0.0f};
  /// The stock's surface was met within the sample's share (else material, or air, goes on
  /// past the medial axis).
  bool surfaceMet = true;
};

/// A closed part, ready for distance queries from any number of threads.
class Part {
 public:
  /// Read `path`: a mesh file, or a .vdb holding a level set (its first float grid of class
  /// level set, meshed at its zero surface). Throws Error for a missing or unreadable file,
  /// ParameterError for an open mesh, one with no triangles or a .vdb without a level set.
  static Part fromFile(const std::string& path);
  /// A part from a closed mesh (mm). Throws ParameterError as fromFile.
  explicit Part(TriangleMesh mesh, const std::string& name = "the part");
  Part(Part&&) noexcept;
  Part& operator=(Part&&) noexcept;
  ~Part();

  const TriangleMesh& mesh() const;
  Box3 bounds() const;
  /// Area of the surface, mm^2.
  double area() const;
  /// Volume inside, mm^3.
  double volume() const;
  /// Distance from p to the part's surface, mm.
  double distance(const Eigen::Vector3d& p) const;
  /// The same, given a point of the part's surface near p (a sample's centre: the search
  /// starts from within that distance).
  double distance(const Eigen::Vector3d& p, const Eigen::Vector3d& onPart) const;
  /// The point of the part's surface nearest p, given a point of it near p.
  Eigen::Vector3d closestPoint(const Eigen::Vector3d& p, const Eigen::Vector3d& onPart) const;
  /// Signed distance: negative inside the part.
  double signedDistance(const Eigen::Vector3d& p) const;
  /// The surface in samples no longer than `spacing` across (each triangle split at the midpoint
  /// of its longest edge until every edge is no longer than it), in the order of the triangles.
  std::vector<PartSample> samples(double spacing) const;
  /// How many samples samples(spacing) makes, without making them.
  std::size_t sampleCount(double spacing) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The stock against the part at every sample: from the sample along its normal (outward where
/// the sample lies in material, inward where in air) in steps of half a cell to the first
/// change, found by bisection to 1e-4 of a cell, cut at the part's medial axis (checked at
/// distances doubling from two cells, then by bisection). The same whatever the thread
/// count. `stop`, asked every few thousand samples: when it says true the rest is left
/// unmeasured (the caller throws). `holds`: no material lies outside this box (a box stock's,
/// exactly: a stock's bounds are rounded out to its cells, and its reading near them is a fraction
/// of a cell off).
std::vector<SampleDeviation> measureDeviation(const Part& part,
                                              const std::vector<PartSample>& samples,
                                              const Stock& stock, const Box3* holds = nullptr,
                                              const std::function<bool()>& stop = {});

/// The mesh of a .vdb level set's zero surface (PartFiles.cpp). Throws as Part::fromFile.
TriangleMesh levelSetMesh(const std::string& path);

/// Write `path` (.vdb, through a temporary file) with a float grid "deviation" of voxel size
/// `cell`: at the voxel of each point, its value in mm (where points share a voxel, the one of
/// largest magnitude). Throws Error.
void writeDeviationVdb(const std::string& path, const std::vector<Eigen::Vector3f>& points,
                       const std::vector<float>& values, double cell);

}  // namespace engage

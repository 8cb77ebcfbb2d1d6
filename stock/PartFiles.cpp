// The part's OpenVDB files (Part.h): a level set read as the part, the deviation grid written.

#include "stock/Part.h"

#include "cutters/Error.h"
#include "stock/VoxelGrid.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <cmath>
#include <cstdlib>

namespace engage {

TriangleMesh levelSetMesh(const std::string& path) {
  voxel::initVdb();
  openvdb::GridPtrVecPtr grids;
  try {
    openvdb::io::File file(path);
    file.open();
    grids = file.getGrids();
    file.close();
  } catch (const openvdb::Exception& e) {
    throw Error(path + ": not a readable .vdb file (" + e.what() + ")");
  }
  for (const openvdb::GridBase::Ptr& g : *grids) {
    const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
    if (!grid || grid->getGridClass() != openvdb::GRID_LEVEL_SET) continue;
    TriangleMesh mesh = voxel::isoSurface(*grid, 0.0, 0.0);
    if (mesh.triangles.empty())
      throw ParameterError(path + ": the level set \"" + grid->getName() + "\" has no surface");
    return mesh;
  }
  throw ParameterError(path +
                       ": no level set in the file (a float grid of class level set, negative "
                       "inside the part)");
}

void writeDeviationVdb(const std::string& path, const std::vector<Eigen::Vector3f>& points,
                       const std::vector<float>& values, double cell) {
  voxel::initVdb();
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("deviation");
  grid->setTransform(openvdb::math::Transform::createLinearTransform(cell));
  grid->setGridClass(openvdb::GRID_UNKNOWN);
  grid->insertMeta("units", openvdb::StringMetadata("mm"));
  grid->insertMeta("meaning",
                   openvdb::StringMetadata("distance from the part's surface to the final "
                                           "stock's, along the part's outward normal: > 0 "
                                           "material left on the part, < 0 the part's material "
                                           "removed (a gouge)"));
  auto acc = grid->getAccessor();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const openvdb::Coord c(static_cast<int>(std::lround(points[i].x() / cell)),
                           static_cast<int>(std::lround(points[i].y() / cell)),
                           static_cast<int>(std::lround(points[i].z() / cell)));
    float v = 0.0f;
    if (!acc.probeValue(c, v) || std::abs(values[i]) > std::abs(v)) acc.setValue(c, values[i]);
  }
  voxel::writeVdb(path, {grid});
}

}  // namespace engage

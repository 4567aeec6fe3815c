#include "mesh/vdb.h"

#include <unistd.h>

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/MeshToVolume.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>

#include "util/error.h"
#include "util/io.h"

namespace quijibo::mesh {

namespace {

void InitializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// voxel (i, j, k) centre == grid.cell_center(i, j, k); see vdb.h.
openvdb::math::Transform::Ptr CellCentredTransform(const GridFrame& frame) {
  auto xform = openvdb::math::Transform::createLinearTransform(frame.spacing);
  xform->postTranslate(openvdb::Vec3d(frame.min_corner[0] + 0.5 * frame.spacing,
                                      frame.min_corner[1] + 0.5 * frame.spacing,
                                      frame.min_corner[2] + 0.5 * frame.spacing));
  return xform;
}

}  // namespace

namespace {

// One grid to `path` as a .vdb file, written to memory first so a failure leaves no file.
void WriteGridAtomically(const std::string& path, const openvdb::FloatGrid::Ptr& vdb) {
  std::ostringstream bytes(std::ios::binary);
  try {
    openvdb::io::Stream(bytes).write(openvdb::GridCPtrVec{vdb});
  } catch (const std::exception& e) {
    throw Error(path + ": cannot write VDB: " + e.what());
  }
  WriteFileAtomically(path, std::move(bytes).str());
}

}  // namespace

void WriteVdb(const std::string& path, const ScalarGrid& grid, const std::string& name) {
  if (const std::string why = grid.frame.Validate(); !why.empty())
    throw Error(path + ": cannot write VDB: " + why);
  if (std::int64_t(grid.values.size()) != grid.frame.cell_count())
    throw Error(path + ": cannot write VDB: value count does not match the grid");
  InitializeOpenVdb();
  const bool level_set = grid.quantity == "signed-distance";
  const double top = grid.values.empty()
                         ? 0.0
                         : *std::max_element(grid.values.begin(), grid.values.end());
  auto vdb = openvdb::FloatGrid::create(level_set ? float(std::max(top, 0.0)) : 0.0f);
  vdb->setTransform(CellCentredTransform(grid.frame));
  vdb->setName(name);
  vdb->setGridClass(level_set ? openvdb::GRID_LEVEL_SET : openvdb::GRID_FOG_VOLUME);
  vdb->insertMeta("quijibo_quantity", openvdb::StringMetadata(grid.quantity));
  vdb->insertMeta("quijibo_coordinates", openvdb::StringMetadata(grid.coordinates));
  auto acc = vdb->getAccessor();
  const auto& d = grid.frame.dims;
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j)
      for (int i = 0; i < d[0]; ++i)
        acc.setValueOn(openvdb::Coord(i, j, k), float(grid.values[grid.frame.index(i, j, k)]));
  WriteGridAtomically(path, vdb);
}

namespace {

openvdb::FloatGrid::Ptr SparseGrid(const std::string& path, const Vec3& origin, double spacing,
                                   const std::vector<std::array<int, 3>>& voxels, const std::vector<float>& values,
                                   float background, double iso, const std::string& name, const std::string& quantity,
                                   const std::string& coordinates) {
  if (voxels.size() != values.size()) throw Error(path + ": cannot write VDB: voxel and value counts differ");
  if (!(spacing > 0) || !std::isfinite(spacing)) throw Error(path + ": cannot write VDB: bad spacing");
  InitializeOpenVdb();
  auto vdb = openvdb::FloatGrid::create(background);
  auto xform = openvdb::math::Transform::createLinearTransform(spacing);
  xform->postTranslate(openvdb::Vec3d(origin[0], origin[1], origin[2]));
  vdb->setTransform(xform);
  vdb->setName(name);
  vdb->setGridClass(openvdb::GRID_FOG_VOLUME);
  vdb->insertMeta("quijibo_quantity", openvdb::StringMetadata(quantity));
  vdb->insertMeta("quijibo_coordinates", openvdb::StringMetadata(coordinates));
  vdb->insertMeta("quijibo_iso", openvdb::DoubleMetadata(iso));
  auto acc = vdb->getAccessor();
  for (std::size_t n = 0; n < voxels.size(); ++n)
    acc.setValueOn(openvdb::Coord(voxels[n][0], voxels[n][1], voxels[n][2]), values[n]);
  return vdb;
}

}  // namespace

void WriteVdbSparse(const std::string& path, const Vec3& origin, double spacing,
                    const std::vector<std::array<int, 3>>& voxels, const std::vector<float>& values,
                    float background, double iso, const std::string& name, const std::string& quantity,
                    const std::string& coordinates) {
  WriteGridAtomically(path, SparseGrid(path, origin, spacing, voxels, values, background, iso, name, quantity,
                                       coordinates));
}

struct SparseVdbBuilder::Impl {
  openvdb::FloatGrid::Ptr grid;
  openvdb::FloatGrid::Accessor acc;
  explicit Impl(openvdb::FloatGrid::Ptr g) : grid(std::move(g)), acc(grid->getAccessor()) {}
};

SparseVdbBuilder::SparseVdbBuilder(const Vec3& origin, double spacing, float background, double iso,
                                   const std::string& name, const std::string& quantity,
                                   const std::string& coordinates) {
  impl_ = std::make_unique<Impl>(SparseGrid(name, origin, spacing, {}, {}, background, iso, name, quantity, coordinates));
}

SparseVdbBuilder::~SparseVdbBuilder() = default;

void SparseVdbBuilder::Add(const std::vector<std::array<int, 3>>& voxels, const std::vector<float>& values) {
  if (voxels.size() != values.size()) throw Error("VDB: voxel and value counts differ");
  for (std::size_t n = 0; n < voxels.size(); ++n)
    impl_->acc.setValueOn(openvdb::Coord(voxels[n][0], voxels[n][1], voxels[n][2]), values[n]);
}

void SparseVdbBuilder::Write(const std::string& path) const {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) throw Error(path + ": cannot write VDB: cannot create " + tmp);
      openvdb::io::Stream(out).write(openvdb::GridCPtrVec{impl_->grid});
      out.flush();
      if (!out) throw Error(path + ": cannot write VDB: write failed");
    }
    std::filesystem::rename(tmp, path);
  } catch (const Error&) {
    std::filesystem::remove(tmp);
    throw;
  } catch (const std::exception& e) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw Error(path + ": cannot write VDB: " + e.what());
  }
}

std::int64_t SparseVdbBuilder::memory_bytes() const { return std::int64_t(impl_->grid->memUsage()); }
std::int64_t SparseVdbBuilder::active_voxels() const { return std::int64_t(impl_->grid->activeVoxelCount()); }

std::string VdbVolumeOptions::Validate() const {
  if (!(voxel_size > 0) || !std::isfinite(voxel_size)) return "the voxel size must be finite and > 0";
  if (!(half_width >= 1) || !(half_width <= 1000)) return "the band half-width must be in [1, 1000] voxels";
  return {};
}

void WriteVdbVolumes(const std::string& path, const TriangleMesh& mesh, const VdbVolumeOptions& o,
                     const VdbRawField* raw) {
  if (auto why = o.Validate(); !why.empty()) throw Error(path + ": cannot write VDB: " + why);
  if (!o.surface && !o.density && !raw) throw Error(path + ": cannot write VDB: no grid asked for");
  InitializeOpenVdb();
  openvdb::GridPtrVec grids;
  if (o.surface || o.density) {
    if (mesh.triangles.empty()) throw Error(path + ": cannot write VDB: the mesh has no triangles");
    const auto xform = openvdb::math::Transform::createLinearTransform(o.voxel_size);
    std::vector<openvdb::Vec3s> points;
    points.reserve(mesh.vertices.size());
    for (const Vec3& v : mesh.vertices) points.emplace_back(float(v[0]), float(v[1]), float(v[2]));  // world
    std::vector<openvdb::Vec3I> triangles;
    triangles.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
    const float w = float(o.half_width);
    openvdb::FloatGrid::Ptr surface;
    try {
      surface = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xform, points, triangles, w);
    } catch (const std::exception& e) {
      throw Error(path + ": cannot build the level set: " + e.what());
    }
    surface->setName("surface");
    surface->setGridClass(openvdb::GRID_LEVEL_SET);
    surface->insertMeta("quijibo_quantity", openvdb::StringMetadata("signed-distance"));
    surface->insertMeta("quijibo_coordinates", openvdb::StringMetadata(o.coordinates));
    if (o.density) {
      // 1 on the interior (tiles included), then the ramp on the band.
      const float band = float(o.half_width * o.voxel_size);
      auto density = openvdb::FloatGrid::create(0.0f);
      density->setTransform(surface->transform().copy());
      density->topologyUnion(*openvdb::tools::sdfInteriorMask(*surface));
      for (auto it = density->beginValueOn(); it; ++it) it.setValue(1.0f);
      auto acc = density->getAccessor();
      for (auto it = surface->cbeginValueOn(); it; ++it) {
        const float ramp = std::clamp(0.5f - *it / (2.0f * band), 0.0f, 1.0f);
        if (it.isVoxelValue()) {
          if (ramp > 0.0f) acc.setValueOn(it.getCoord(), ramp);
          else acc.setValueOff(it.getCoord(), 0.0f);
        }
      }
      density->pruneGrid();
      density->setName("density");
      density->setGridClass(openvdb::GRID_FOG_VOLUME);
      density->insertMeta("quijibo_quantity", openvdb::StringMetadata("density"));
      density->insertMeta("quijibo_coordinates", openvdb::StringMetadata(o.coordinates));
      grids.push_back(density);
    }
    if (o.surface) grids.insert(grids.begin(), surface);
  }
  if (raw) {
    if (!raw->voxels || !raw->values) throw Error(path + ": cannot write VDB: the raw field has no samples");
    grids.push_back(SparseGrid(path, raw->origin, raw->spacing, *raw->voxels, *raw->values, raw->background, raw->iso,
                               raw->name, raw->quantity, o.coordinates));
  }
  std::ostringstream bytes(std::ios::binary);
  try {
    openvdb::io::Stream(bytes).write(grids);
  } catch (const std::exception& e) {
    throw Error(path + ": cannot write VDB: " + e.what());
  }
  WriteFileAtomically(path, std::move(bytes).str());
}

ScalarGrid ReadVdb(const std::string& path, const std::string& name) {
  InitializeOpenVdb();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open VDB file");
  openvdb::GridPtrVecPtr grids;
  try {
    grids = openvdb::io::Stream(in).getGrids();
  } catch (const std::exception& e) {
    throw Error(path + ": not a readable VDB file: " + e.what());
  }
  openvdb::FloatGrid::Ptr vdb;
  for (const auto& g : *grids) {
    auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
    if (f && (name.empty() || f->getName() == name)) {
      vdb = f;
      break;
    }
  }
  if (!vdb)
    throw Error(path + ": no float grid" + (name.empty() ? std::string() : " named '" + name + "'"));
  const auto& xform = vdb->transform();
  const openvdb::Vec3d voxel = xform.voxelSize();
  if (!xform.isLinear() || !xform.hasUniformScale() ||
      std::abs(voxel[0] - voxel[1]) > 1e-12 * voxel[0])
    throw Error(path + ": grid '" + vdb->getName() + "' does not have a uniform linear transform");
  const openvdb::CoordBBox box = vdb->evalActiveVoxelBoundingBox();
  if (box.empty()) throw Error(path + ": grid '" + vdb->getName() + "' has no active voxels");
  ScalarGrid out;
  out.frame.spacing = voxel[0];
  const openvdb::Vec3d lo = xform.indexToWorld(box.min());
  for (int a = 0; a < 3; ++a) {
    out.frame.dims[a] = box.dim()[a];
    out.frame.min_corner[a] = lo[a] - 0.5 * voxel[0];
  }
  if (auto m = vdb->getMetadata<openvdb::StringMetadata>("quijibo_quantity")) out.quantity = m->value();
  if (auto m = vdb->getMetadata<openvdb::StringMetadata>("quijibo_coordinates"))
    out.coordinates = m->value();
  out.values.resize(std::size_t(out.frame.cell_count()));
  auto acc = vdb->getConstAccessor();
  for (int k = 0; k < out.frame.dims[2]; ++k)
    for (int j = 0; j < out.frame.dims[1]; ++j)
      for (int i = 0; i < out.frame.dims[0]; ++i)
        out.values[out.frame.index(i, j, k)] = acc.getValue(box.min().offsetBy(i, j, k));
  return out;
}

}  // namespace quijibo::mesh

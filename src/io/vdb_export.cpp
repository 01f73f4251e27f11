// The one translation unit that includes OpenVDB (vdb_export.hpp says what a frame holds).
//
// OpenVDB runs its tools on TBB threads; they run in an arena of as many threads as the run's
// OpenMP (--threads), so that an export never takes more cores than the simulation was given.
#include "io/vdb_export.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <omp.h>
#include <openvdb/io/Archive.h>
#include <openvdb/openvdb.h>
#include <openvdb/points/PointAttribute.h>
#include <openvdb/points/PointConversion.h>
#include <openvdb/points/PointDataGrid.h>
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/ParticlesToLevelSet.h>
#include <openvdb/tools/PointIndexGrid.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <tbb/task_arena.h>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "io/export_formats.hpp"

namespace sandflow {
namespace {

namespace vdb = openvdb;

vdb::Vec3d to_vdb(const Vec3& v) {
  return {v.x, v.y, v.z};
}

// The grains as spheres, in the exported frame: the particle list ParticlesToLevelSet reads.
class GrainSpheres {
 public:
  using PosType = vdb::Vec3R;
  GrainSpheres(const FrameData& f, UpAxis up) : f_(f), up_(up) {}
  std::size_t size() const { return f_.size(); }
  void getPos(std::size_t n, vdb::Vec3R& x) const { x = to_vdb(to_up_axis(f_.position[n], up_)); }
  void getPosRad(std::size_t n, vdb::Vec3R& x, vdb::Real& r) const {
    getPos(n, x);
    r = f_.radius[n];
  }
  void getPosRadVel(std::size_t n, vdb::Vec3R& x, vdb::Real& r, vdb::Vec3R& v) const {
    getPosRad(n, x, r);
    v = f_.velocity.empty() ? vdb::Vec3R(0.0) : to_vdb(to_up_axis(f_.velocity[n], up_));
  }

 private:
  const FrameData& f_;
  UpAxis up_;
};

// h and L at a point of the plane, and their slopes, interpolated bilinearly between the four
// nearest column centres, as the height field's OBJ meshes draw them.
struct LayerTops {
  Real h, L;
  Real h_x, h_y, L_x, L_y;  ///< gradients [-]
};

// False outside the grid's rectangle and across a step of the terrain or a wall (a bowl's rim, a
// container's side: HeightField::smooth_square), where interpolation would lay sand up the wall.
bool smooth_tops(const HeightField& hf, Real x, Real y, LayerTops& out) {
  const HeightFieldParams& p = hf.params();
  if (x < p.x0 || x > p.x0 + p.nx * p.cell || y < p.y0 || y > p.y0 + p.ny * p.cell) return false;
  const std::vector<Real>& h = hf.static_top();
  const std::vector<Real>& L = hf.terrain();
  const auto idx = [&](int i, int j) { return static_cast<std::size_t>(j) * p.nx + i; };
  const Real u = std::clamp((x - p.x0) / p.cell - 0.5, 0.0, static_cast<Real>(p.nx - 1));
  const Real v = std::clamp((y - p.y0) / p.cell - 0.5, 0.0, static_cast<Real>(p.ny - 1));
  const int i = std::min(static_cast<int>(u), std::max(p.nx - 2, 0));
  const int j = std::min(static_cast<int>(v), std::max(p.ny - 2, 0));
  const int i1 = std::min(i + 1, p.nx - 1), j1 = std::min(j + 1, p.ny - 1);
  if (!hf.smooth_square(i, j)) return false;
  const Real a = u - i, b = v - j;
  const auto lerp = [&](const std::vector<Real>& z, Real& z_x, Real& z_y) {
    const Real z00 = z[idx(i, j)], z10 = z[idx(i1, j)], z01 = z[idx(i, j1)], z11 = z[idx(i1, j1)];
    z_x = ((1 - b) * (z10 - z00) + b * (z11 - z01)) / p.cell;
    z_y = ((1 - a) * (z01 - z00) + a * (z11 - z10)) / p.cell;
    return (1 - b) * ((1 - a) * z00 + a * z10) + b * ((1 - a) * z01 + a * z11);
  };
  out.h = lerp(h, out.h_x, out.h_y);
  out.L = lerp(L, out.L_x, out.L_y);
  return true;
}

// The static layer's narrow band in `grid` (a level set of voxel vs and half width w), voxel column
// by voxel column of the scene, in the exported frame (with y up, scene voxel (a, b, c) is
// exported voxel (a, c, -b)). Where the layer is smooth (h above L, interpolated), the distance
// to the planes of h and L. Elsewhere (no sand there, a step of the terrain, outside the grid)
// each column is a box from L to h: inside a column's sand, the distance to its top, its bottom
// or the nearest neighbour without sand at that height; outside, to the nearest box of sand.
// The band then reaches past every edge of the layer, encloses it, and the signed flood fill
// finds the inside: only the columns within reach of sand are visited, and the voxels deeper
// inside than w are left to the flood fill.
void add_static_layer(vdb::FloatGrid& grid, const HeightField& hf, Real vs, UpAxis up) {
  const HeightFieldParams& p = hf.params();
  const Real w = kVdbHalfWidth * vs;
  const Real x_lo = p.x0, x_hi = p.x0 + p.nx * p.cell, y_lo = p.y0, y_hi = p.y0 + p.ny * p.cell;
  const std::vector<Real>& h = hf.static_top();
  const std::vector<Real>& L = hf.terrain();
  const auto idx = [&](int i, int j) { return static_cast<std::size_t>(j) * p.nx + i; };
  const auto column_i = [&](Real x) { return static_cast<int>(std::floor((x - p.x0) / p.cell)); };
  const auto column_j = [&](Real y) { return static_cast<int>(std::floor((y - p.y0) / p.cell)); };

  // columns with static sand, widened by the band and the one column a bilinear value reaches
  const int reach = static_cast<int>(std::ceil(w / p.cell)) + 1;
  std::vector<std::uint8_t> near(h.size(), 0);
  bool any = false;
  for (int j = 0; j < p.ny; ++j)
    for (int i = 0; i < p.nx; ++i) {
      if (!(h[idx(i, j)] > L[idx(i, j)])) continue;
      any = true;
      for (int jj = std::max(j - reach, 0); jj <= std::min(j + reach, p.ny - 1); ++jj)
        for (int ii = std::max(i - reach, 0); ii <= std::min(i + reach, p.nx - 1); ++ii)
          near[idx(ii, jj)] = 1;
    }
  if (!any) return;

  auto acc = grid.getAccessor();
  struct NearColumn {
    Real dx, dy;  ///< how far outside the column's rectangle, along x and y (< 0: inside) [m]
    Real h, L;
    bool own;  ///< the column holding the point
  };
  std::vector<NearColumn> near_columns;
  const int a0 = static_cast<int>(std::floor((x_lo - w) / vs));
  const int a1 = static_cast<int>(std::ceil((x_hi + w) / vs));
  const int b0 = static_cast<int>(std::floor((y_lo - w) / vs));
  const int b1 = static_cast<int>(std::ceil((y_hi + w) / vs));
  for (int b = b0; b <= b1; ++b)
    for (int a = a0; a <= a1; ++a) {
      const Real x = a * vs, y = b * vs;
      if (!near[idx(std::clamp(column_i(x), 0, p.nx - 1), std::clamp(column_j(y), 0, p.ny - 1))])
        continue;
      const auto set = [&](int c, Real phi) {
        if (!(std::abs(phi) < w)) return;
        acc.setValue(up == UpAxis::Y ? vdb::Coord(a, c, -b) : vdb::Coord(a, b, c),
                     static_cast<float>(phi));
      };
      LayerTops t;
      if (smooth_tops(hf, x, y, t) && t.h > t.L) {
        // the distance of a point to a plane is its height above it times the cosine of the
        // plane's slope; outside the grid's rectangle there is no static layer
        const Real stretch_h = std::hypot(1.0, t.h_x, t.h_y);  // 1 / cos(slope)
        const Real stretch_L = std::hypot(1.0, t.L_x, t.L_y);
        const Real side = std::max({x_lo - x, x - x_hi, y_lo - y, y - y_hi});
        const int c0 = static_cast<int>(std::floor((t.L - w * stretch_L) / vs));
        const int c1 = static_cast<int>(std::ceil((t.h + w * stretch_h) / vs));
        for (int c = c0; c <= c1; ++c) {
          const Real z = c * vs;
          set(c, std::max({(z - t.h) / stretch_h, (t.L - z) / stretch_L, side}));
        }
        continue;
      }
      // Columns as boxes from L to h: inside a column's sand, the distance to its top, its
      // bottom or the nearest neighbour without sand at that height; outside, to the nearest
      // box of sand (exact for one box; the nearest is what the band needs)
      near_columns.clear();
      const int own_i = column_i(x), own_j = column_j(y);
      const bool in_grid = own_i >= 0 && own_i < p.nx && own_j >= 0 && own_j < p.ny;
      const std::size_t own = in_grid ? idx(own_i, own_j) : 0;
      const bool own_sand = in_grid && h[own] > L[own];
      Real z_lo = std::numeric_limits<Real>::infinity(), z_hi = -z_lo;
      const int i0 = std::max(column_i(x - w), 0), i1 = std::min(column_i(x + w), p.nx - 1);
      const int j0 = std::max(column_j(y - w), 0), j1 = std::min(column_j(y + w), p.ny - 1);
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const std::size_t k = idx(i, j);
          // how far outside the column's rectangle (x, y) lies, each way (< 0: inside)
          const Real dx = std::abs(x - (p.x0 + (i + 0.5) * p.cell)) - 0.5 * p.cell;
          const Real dy = std::abs(y - (p.y0 + (j + 0.5) * p.cell)) - 0.5 * p.cell;
          if (std::hypot(std::max(dx, 0.0), std::max(dy, 0.0)) >= w) continue;
          near_columns.push_back({dx, dy, h[k], L[k], in_grid && k == own});
          if (h[k] > L[k]) z_lo = std::min(z_lo, L[k]), z_hi = std::max(z_hi, h[k]);
        }
      if (!(z_hi > z_lo)) continue;
      const int c0 = static_cast<int>(std::floor((z_lo - w) / vs));
      const int c1 = static_cast<int>(std::ceil((z_hi + w) / vs));
      for (int c = c0; c <= c1; ++c) {
        const Real z = c * vs;
        Real phi = std::numeric_limits<Real>::infinity();
        if (own_sand && z > L[own] && z < h[own]) {
          Real depth = std::min(h[own] - z, z - L[own]);
          for (const NearColumn& n : near_columns)
            if (!n.own && !(z > n.L && z < n.h))
              depth = std::min(depth, std::hypot(std::max(n.dx, 0.0), std::max(n.dy, 0.0)));
          phi = -depth;
        } else {
          for (const NearColumn& n : near_columns) {
            if (!(n.h > n.L)) continue;
            const Real dz = std::max(z - n.h, n.L - z);
            const Real out =
                std::hypot(std::max(n.dx, 0.0), std::max(n.dy, 0.0), std::max(dz, 0.0));
            phi = std::min(phi, out + std::min(std::max({n.dx, n.dy, dz}), 0.0));
          }
        }
        set(c, phi);
      }
    }
}

// The "surface" level set: the grains as spheres, and the static layer when there is one.
vdb::FloatGrid::Ptr sand_level_set(const FrameData& f, const HeightField* static_layer,
                                   const VdbFrameInfo& info) {
  const Real vs = info.surface_voxel;
  vdb::FloatGrid::Ptr ls = vdb::createLevelSet<vdb::FloatGrid>(vs, kVdbHalfWidth);
  if (f.size() > 0) {
    vdb::tools::ParticlesToLevelSet<vdb::FloatGrid> raster(*ls);
    // OpenVDB leaves out spheres under 1.5 voxels (its Nyquist limit): with a coarse voxel the
    // small grains are drawn coarsely instead, never dropped from the surface
    const auto [r_min, r_max] = std::minmax_element(f.radius.begin(), f.radius.end());
    raster.setRmin(std::min(1.5, *r_min / vs));
    // and above 100 voxels (its default cap) it drops them too: never, here (the scene's voxel is
    // at least d / 200, scene_tables.hpp)
    raster.setRmax(std::max(100.0, *r_max / vs));
    raster.rasterizeSpheres(GrainSpheres(f, info.up));
    raster.finalize(/*prune=*/true);
  }
  if (static_layer) {
    vdb::FloatGrid::Ptr layer = vdb::createLevelSet<vdb::FloatGrid>(vs, kVdbHalfWidth);
    add_static_layer(*layer, *static_layer, vs, info.up);
    vdb::tools::signedFloodFill(layer->tree());
    vdb::tools::csgUnion(*ls, *layer, /*prune=*/true);
  }
  return ls;
}

// The "grains" points grid: P (16-bit offsets in a voxel), pscale, v, id, state.
vdb::points::PointDataGrid::Ptr grain_points(const FrameData& f, const VdbFrameInfo& info) {
  namespace pts = vdb::points;
  const std::size_t n = f.size();
  std::vector<vdb::Vec3d> position(n);
  std::vector<float> radius(n);
  std::vector<vdb::Vec3f> velocity(n);
  std::vector<std::int64_t> id(n);
  std::vector<std::int8_t> state(n);
  for (std::size_t i = 0; i < n; ++i) {
    position[i] = to_vdb(to_up_axis(f.position[i], info.up));
    radius[i] = static_cast<float>(f.radius[i]);
    velocity[i] = f.velocity.empty() ? vdb::Vec3f(0.0f)
                                     : vdb::Vec3f(to_vdb(to_up_axis(f.velocity[i], info.up)));
    id[i] = f.id.empty() ? static_cast<std::int64_t>(i) : static_cast<std::int64_t>(f.id[i]);
    state[i] = f.state.empty() ? std::int8_t{0} : static_cast<std::int8_t>(f.state[i]);
  }
  const vdb::math::Transform::Ptr xform =
      vdb::math::Transform::createLinearTransform(info.points_voxel);
  const pts::PointAttributeVector<vdb::Vec3d> positions(position);
  const auto index =
      vdb::tools::createPointIndexGrid<vdb::tools::PointIndexGrid>(positions, *xform);
  auto grid =
      pts::createPointDataGrid<pts::FixedPointCodec</*one_byte=*/false>, pts::PointDataGrid>(
          *index, positions, *xform);
  pts::PointDataTree& tree = grid->tree();
  if (n > 0) {
    const auto add = [&](const char* name, const auto& values) {
      using T = typename std::decay_t<decltype(values)>::value_type;
      pts::appendAttribute<T>(tree, name);
      pts::populateAttribute(tree, index->tree(), name, pts::PointAttributeVector<T>(values));
    };
    add("pscale", radius);
    add("v", velocity);
    add("id", id);
    add("state", state);
  }
  return grid;
}

// io::File writes through an ofstream it never checks after opening it, so a full disk would
// leave a short file that looks whole; the archive is written to memory instead, as File does
// it, and then through the project's atomic writer, which reports any failure.
class MemoryArchive : public vdb::io::Archive {
 public:
  std::string bytes(const vdb::GridCPtrVec& grids, const vdb::MetaMap& meta) const {
    std::ostringstream out(std::ios_base::out | std::ios_base::binary);
    Archive::write(out, grids, /*seekable=*/true, meta);
    return std::move(out).str();
  }
};

}  // namespace

Real vdb_points_voxel(const MaterialConfig& m) {
  return 2 * m.diameter;
}

Real vdb_surface_voxel(const SceneConfig& scene) {
  if (scene.output.vdb_voxel_size) return *scene.output.vdb_voxel_size;
  return scene.material.smallest_diameter() / 3;
}

void write_vdb(const std::string& path, const FrameData& f, const HeightField* static_layer,
               const VdbFrameInfo& info) {
  if (f.radius.size() != f.size() || (!f.velocity.empty() && f.velocity.size() != f.size()) ||
      (!f.id.empty() && f.id.size() != f.size()) ||
      (!f.state.empty() && f.state.size() != f.size()))
    throw std::invalid_argument("write_vdb: FrameData arrays have different lengths");
  if (!(info.points_voxel > 0) || !(info.surface_voxel > 0))
    throw std::invalid_argument("write_vdb: voxel sizes must be positive");
  vdb::initialize();  // registers the grid and attribute types; cheap after the first call

  std::string bytes;
  tbb::task_arena arena(std::max(omp_get_max_threads(), 1));
  try {
    arena.execute([&] {
      vdb::MetaMap meta;
      meta.insertMeta("time", vdb::DoubleMetadata(info.time));
      meta.insertMeta("frame", vdb::Int32Metadata(info.frame));
      meta.insertMeta("scene", vdb::StringMetadata(info.scene));
      meta.insertMeta("units", vdb::StringMetadata("m"));
      meta.insertMeta("up_axis", vdb::StringMetadata(std::string(up_axis_name(info.up))));
      meta.insertMeta("creator", vdb::StringMetadata("sandflow " SANDFLOW_VERSION));

      vdb::points::PointDataGrid::Ptr grains = grain_points(f, info);
      grains->setName(std::string(kVdbGrainsGrid));
      vdb::FloatGrid::Ptr surface = sand_level_set(f, static_layer, info);
      surface->setName(std::string(kVdbSurfaceGrid));
      // stored as 16-bit floats: within 2^-11 of the band's half width (a few micrometres),
      // half the bytes
      surface->setSaveFloatAsHalf(true);
      for (vdb::GridBase* g :
           {static_cast<vdb::GridBase*>(grains.get()), static_cast<vdb::GridBase*>(surface.get())})
        for (auto m = meta.beginMeta(); m != meta.endMeta(); ++m)
          g->insertMeta(m->first, *m->second);
      bytes = MemoryArchive().bytes({grains, surface}, meta);
    });
  } catch (const vdb::Exception& e) {
    throw OutputError(path + ": cannot make the VDB grids: " + e.what());
  }
  write_file_atomic(path, bytes, Sync::Later);
}

}  // namespace sandflow

// Mesh obstacles from scene entries: find the file, load it, scale, rotate and set it down where
// the scene says, and tell the user what they should know about it.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/file_kind.hpp"
#include "geometry/mesh_io.hpp"
#include "geometry/mesh_sampling.hpp"
#include "geometry/shapes.hpp"

namespace sandflow {

namespace {

namespace fs = std::filesystem;

// Beside the scene, then $SANDFLOW_MESH_DIR, then .cache/meshes/ beside the scene's folder.
std::vector<fs::path> mesh_candidates(const std::string& file, const std::string& scene_path) {
  const fs::path f(file);
  if (f.is_absolute()) return {f};
  const fs::path dir = fs::path(scene_path).parent_path();
  std::vector<fs::path> out{dir / f};
  if (const char* env = std::getenv("SANDFLOW_MESH_DIR"); env && *env) out.push_back(fs::path(env) / f);
  out.push_back((dir.empty() ? fs::path("..") : dir / "..") / ".cache" / "meshes" / f);
  return out;
}

// A closed box [-s/2, s/2] x [-s/2, s/2] x [0, s] around the origin, outward counter-clockwise.
TriangleMesh box_mesh(const Vec3& size) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.push_back({(i & 1 ? 0.5 : -0.5) * size.x, (i & 2 ? 0.5 : -0.5) * size.y,
                          (i & 4 ? 1.0 : 0.0) * size.z});
  // faces as quads (a, b, c, d) counter-clockwise seen from outside
  const std::uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                 {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : q) {
    m.triangles.push_back({f[0], f[1], f[2]});
    m.triangles.push_back({f[0], f[2], f[3]});
  }
  return m;
}

}  // namespace

MeshObstacle place_mesh(const GeometryConfig& c, const MaterialConfig& material,
                        const std::string& scene_path, std::vector<std::string>& warnings,
                        Real sample_budget) {
  MeshObstacle o;
  o.name = c.name;
  o.friction = c.friction.value_or(material.wall_friction);
  o.rolling_friction = material.wall_rolling_friction;
  o.twisting_friction = material.wall_twisting_friction;
  const Real d_min = material.smallest_diameter();
  o.particle_radius = c.particle_radius.value_or(0.5 * d_min);

  std::string found;
  std::string looked;
  for (const fs::path& p : mesh_candidates(c.mesh_file, scene_path)) {
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) {
      found = p.string();
      break;
    }
    if (fs::exists(p, ec))  // (a FIFO or a device: never read, and never "not found")
      throw InputError(fmt::format("{}: {}: the mesh file '{}' is {}, not a file", scene_path,
                                   c.name, p.string(), special_file_kind(p.string())));
    try {  // (a link to nothing is a mount or a file gone, not a mesh never fetched)
      refuse_broken_link(p.string(), "mesh file");
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: {}: {}", scene_path, c.name, e.what()));
    }
    looked += (looked.empty() ? "" : ", ") + p.string();
  }
  if (found.empty()) {
    if (!c.fallback_box)
      throw InputError(fmt::format(
          "{}: {}: mesh file '{}' not found (looked in {}); run scripts/fetch_meshes.sh for the "
          "sample meshes, or set fallback = \"box\"",
          scene_path, c.name, c.mesh_file, looked));
    warnings.push_back(fmt::format(
        "{}: mesh file '{}' not found (looked in {}); a box of {} x {} x {} m stands in for it. "
        "Run scripts/fetch_meshes.sh to fetch the sample meshes.",
        c.name, c.mesh_file, looked, c.fallback_size.x, c.fallback_size.y, c.fallback_size.z));
    o.mesh = box_mesh(c.fallback_size);
    transform(o.mesh, 1.0, c.rotation_deg, c.position);
  } else {
    o.mesh = load_mesh(found);
    // scale, rotate about the origin, then set the bottom centre of its bounds at `position`
    Aabb box = mesh_bounds(o.mesh);
    const Vec3 ext = box.hi - box.lo;
    const Real largest = std::max({ext.x, ext.y, ext.z});
    if (!(largest > 0)) throw InputError(fmt::format("{}: {}: the mesh is flat or empty", found, c.name));
    if (!std::isfinite(largest))
      throw InputError(fmt::format("{}: {}: the mesh's coordinates are too large: its extent is "
                                   "not a finite number of metres",
                                   found, c.name));
    const Real scale = c.scale ? *c.scale : (c.mesh_size ? *c.mesh_size / largest : 1.0);
    transform(o.mesh, scale, c.rotation_deg, Vec3{});
    box = mesh_bounds(o.mesh);
    const Vec3 bottom_centre{0.5 * (box.lo.x + box.hi.x), 0.5 * (box.lo.y + box.hi.y), box.lo.z};
    transform(o.mesh, 1.0, Vec3{}, c.position - bottom_centre);
    const MeshQuality q = mesh_quality(o.mesh);
    if (!q.closed())
      warnings.push_back(fmt::format(
          "{}: the mesh '{}' is open ({} boundary edges): the inside test is a winding number, "
          "robust to holes, and the grains collide with its sampled surface either way",
          c.name, found, q.boundary_edges));
  }
  // Everything after (edge lengths, the boundary particles and their grid, the domain) needs the
  // placed mesh finite and near enough to the origin for a double to resolve its particles.
  const Aabb placed = mesh_bounds(o.mesh);
  const Real far = kMaxMeshSpacingsFromOrigin * 0.5 * o.particle_radius;
  for (int a = 0; a < 3; ++a)
    if (!(std::abs(placed.lo[a]) <= far && std::abs(placed.hi[a]) <= far))
      throw InputError(fmt::format(
          "{}: {}: the placed mesh reaches from ({:.4g}, {:.4g}, {:.4g}) to ({:.4g}, {:.4g}, "
          "{:.4g}) m, beyond {:.4g} m from the origin (2^40 particle spacings) on some axis; check "
          "its scale, size and position",
          scene_path, c.name, placed.lo.x, placed.lo.y, placed.lo.z, placed.hi.x, placed.hi.y,
          placed.hi.z, far));
  // (counted before the inside test's tree, which takes more than the mesh itself)
  try {
    o.sample_count = check_surface_sample_count(o.mesh, o.sample_spacing(), sample_budget);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}: {}", scene_path, c.name, e.what()));
  }
  o.winding = std::make_unique<WindingNumber>(o.mesh);
  return o;
}

}  // namespace sandflow

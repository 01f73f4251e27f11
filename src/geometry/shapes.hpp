// Analytic geometry the grains collide with (docs/design.md §6): every shape is a solid described by a
// signed distance (positive outside) and its outward normal, so one contact routine serves all.
// A container (a box or a cylinder that holds grains) is made of solid wall slabs.
#pragma once

#include <algorithm>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "config/scene_config.hpp"
#include "core/vec3.hpp"
#include "geometry/mesh.hpp"
#include "geometry/mesh_sampling.hpp"
#include "geometry/winding_number.hpp"

namespace sandflow {

struct SurfacePoint {
  Real distance;  ///< signed distance from the solid (negative inside) [m]
  Vec3 normal;    ///< outward unit normal of the solid at the closest point
};

/// Stretches [bottom, top] of a vertical line, ascending.
using Stretches = std::vector<std::pair<Real, Real>>;

/// A solid primitive.
class Solid {
 public:
  virtual ~Solid() = default;
  virtual SurfacePoint closest(const Vec3& p) const = 0;
  /// Axis-aligned bounds of the solid (infinite for a half-space).
  virtual void bounds(Vec3& lo, Vec3& hi) const = 0;
  /// The stretches of the vertical line at (x, y) inside the solid (its boundary included),
  /// ascending, appended to `out`, in closed form; an end is infinite where the solid goes on.
  virtual void vertical_stretches(Real x, Real y, Stretches& out) const = 0;
  /// The least width across the solid (a container wall's thickness): vertical lines closer
  /// together than that cannot pass it by. Infinite for a half-space and a heightmap, whose
  /// relief is the columns' own.
  virtual Real least_width() const = 0;
};

class HalfSpace final : public Solid {
 public:
  HalfSpace(const Vec3& point, const Vec3& normal) : point_(point), normal_(normal) {}
  SurfacePoint closest(const Vec3& p) const override { return {dot(p - point_, normal_), normal_}; }
  void bounds(Vec3& lo, Vec3& hi) const override;
  void vertical_stretches(Real x, Real y, Stretches& out) const override;
  Real least_width() const override { return std::numeric_limits<Real>::infinity(); }

 private:
  Vec3 point_, normal_;
};

/// What a removed solid becomes (Geometry::remove_source): infinitely far from every point.
class RemovedSolid final : public Solid {
 public:
  SurfacePoint closest(const Vec3&) const override {
    return {std::numeric_limits<Real>::infinity(), {0, 0, 1}};
  }
  void bounds(Vec3& lo, Vec3& hi) const override;  ///< empty: lo = +inf, hi = -inf
  void vertical_stretches(Real x, Real y, Stretches& out) const override;
  Real least_width() const override { return std::numeric_limits<Real>::infinity(); }
};

/// An oriented solid box.
class SolidBox final : public Solid {
 public:
  SolidBox(const Vec3& center, const Vec3& half, const Mat3& rotation);
  SurfacePoint closest(const Vec3& p) const override;
  void bounds(Vec3& lo, Vec3& hi) const override;
  void vertical_stretches(Real x, Real y, Stretches& out) const override;
  Real least_width() const override { return 2 * std::min({half_.x, half_.y, half_.z}); }

 private:
  Vec3 center_, half_;
  Mat3 rot_, rot_t_;  ///< local -> world, world -> local
};

class SolidSphere final : public Solid {
 public:
  SolidSphere(const Vec3& center, Real radius) : center_(center), radius_(radius) {}
  SurfacePoint closest(const Vec3& p) const override;
  void bounds(Vec3& lo, Vec3& hi) const override;
  void vertical_stretches(Real x, Real y, Stretches& out) const override;
  Real least_width() const override { return 2 * radius_; }

 private:
  Vec3 center_;
  Real radius_;
};

/// A finite solid cylinder, or a thick tube (inner_radius > 0), along its local z axis.
class SolidCylinder final : public Solid {
 public:
  SolidCylinder(const Vec3& center, Real radius, Real inner_radius, Real height,
                const Mat3& rotation);
  SurfacePoint closest(const Vec3& p) const override;
  void bounds(Vec3& lo, Vec3& hi) const override;
  void vertical_stretches(Real x, Real y, Stretches& out) const override;
  Real least_width() const override;

 private:
  Vec3 center_;
  Real radius_, inner_radius_, half_height_;
  Mat3 rot_, rot_t_;
};

/// A hemispherical bowl, or any spherical cap of a shell: the solid between the spheres of radius
/// `radius` (the inside the grains see) and `radius + thickness` around `center`, below the rim
/// plane. The rim plane is `depth` above the lowest inner point, so it lies at local
/// z = depth - radius: through the centre for depth = radius (a hemisphere), below it for a
/// shallower dish, above it for a deeper bowl. `rotation` turns the bowl about its centre.
class SolidBowl final : public Solid {
 public:
  SolidBowl(const Vec3& center, Real radius, Real thickness, Real depth, const Mat3& rotation);
  /// Exact signed distance: the cross-section in the (radial, axial) half-plane is an annulus cut
  /// by a line, whose boundary is two arcs and the flat rim.
  SurfacePoint closest(const Vec3& p) const override;
  void bounds(Vec3& lo, Vec3& hi) const override;
  void vertical_stretches(Real x, Real y, Stretches& out) const override;
  Real least_width() const override { return outer_ - inner_; }

 private:
  Vec3 center_;
  Real inner_, outer_;          ///< radii of the inner and outer spheres [m]
  Real rim_z_;                  ///< local height of the rim plane above the centre [m]
  Real rim_in_, rim_out_;       ///< radial extent of the flat rim [m]
  Mat3 rot_, rot_t_;
};

/// A solid plus the contact properties of its surface.
struct Obstacle {
  std::unique_ptr<Solid> solid;
  Real friction = 0.6;          ///< Coulomb friction with grains [-]
  Real rolling_friction = 0.1;  ///< [-]
  Real twisting_friction = 0;   ///< [-]
  int source = 0;               ///< index of the [[geometry]] entry it came from
};

/// A mesh obstacle, placed. Grains collide with its boundary particles (DemSolver), spheres of
/// `particle_radius` sampled over its surface; its winding number counts grains that got inside.
struct MeshObstacle {
  std::string name;
  TriangleMesh mesh;
  std::unique_ptr<WindingNumber> winding;
  Real particle_radius = 0;  ///< [m]
  Real friction = 0.6, rolling_friction = 0.1, twisting_friction = 0;
  int source = 0;
  Real sample_count = 0;  ///< samples its sampling makes before merging

  /// Its boundary particles' sampling: every surface point within 0.99 r_b of a particle's
  /// centre (spacing r_b / 2, merged within 0.7 r_b: geometry/mesh_sampling.hpp), so that no
  /// grain can touch the mesh without overlapping one; the merge keeps a fine scan from giving a
  /// particle per vertex.
  Real sample_spacing() const { return 0.5 * particle_radius; }
  Real sample_merge() const { return 0.7 * particle_radius; }
};

/// Loads, places and checks the mesh of a `type = "mesh"` entry (see Geometry::from_config for
/// where its file is looked for); a missing file gives the entry's fallback box, with a warning.
/// `sample_budget`: the boundary particles (counted before merging) the mesh may take.
MeshObstacle place_mesh(const GeometryConfig& c, const MaterialConfig& material,
                        const std::string& scene_path, std::vector<std::string>& warnings,
                        Real sample_budget = static_cast<Real>(kMaxSurfaceSamples));

/// Every solid of a scene. Containers expand into several wall slabs.
class Geometry {
 public:
  /// Mesh files are looked for beside the scene file `scene_path`, then in the folder named by
  /// the environment variable SANDFLOW_MESH_DIR, then in .cache/meshes/ beside the scene's
  /// folder (where scripts/fetch_meshes.sh puts them).
  static Geometry from_config(const std::vector<GeometryConfig>& configs,
                              const MaterialConfig& material, const std::string& scene_path = "");

  void add(std::unique_ptr<Solid> solid, Real friction, Real rolling_friction,
           Real twisting_friction, int source);
  /// Removes the solids of the [[geometry]] entry `source` (its remove_at has come): they stay in
  /// the list, so obstacle indices keep their meaning, but reach nothing from then on. Returns
  /// how many there were.
  int remove_source(int source);

  const std::vector<Obstacle>& obstacles() const { return obstacles_; }
  std::size_t size() const { return obstacles_.size(); }

  /// Height of the highest surface of a primitive solid met going down the vertical line at
  /// (x, y) from z_from (z_from itself when it starts inside one), or z_floor when there is none
  /// above it. Meshes are not asked: a pour's fall measured past a mesh to the ground under it
  /// bounds the speed of the grains that run off the mesh onto that ground (stiffness, a throw's
  /// landing, a frame's camera). Where sand lies on a mesh, ask solid_intervals.
  Real top_below(Real x, Real y, Real z_from, Real z_floor) const;
  /// The solid intervals [bottom, top] along the vertical line at (x, y) between z_floor and
  /// z_from, ascending (a bottom at or below z_floor is -infinity: the solid goes on down), the
  /// union of the solids' stretches (Solid::vertical_stretches) and the meshes'. `queries`, when
  /// given, is increased by the solids and meshes it asked: what the tracing cost.
  std::vector<std::pair<Real, Real>> solid_intervals(Real x, Real y, Real z_from, Real z_floor,
                                                     std::uint64_t* queries = nullptr) const;
  /// Union of the bounds of the finite solids; false when every solid is infinite (or none).
  bool finite_bounds(Vec3& lo, Vec3& hi) const;

  /// Number of grains whose centre lies inside a solid or a mesh (should be 0).
  std::size_t count_inside(const std::vector<Vec3>& x) const;

  const std::vector<MeshObstacle>& meshes() const { return meshes_; }
  /// What the user should know (a mesh replaced by its fallback, an open mesh).
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  std::vector<Obstacle> obstacles_;
  std::vector<MeshObstacle> meshes_;
  std::vector<std::string> warnings_;
};

}  // namespace sandflow

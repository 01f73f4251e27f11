#include "geometry/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "core/error.hpp"
#include "geometry/heightmap.hpp"
#include "geometry/mesh_io.hpp"

namespace sandflow {

namespace {
constexpr Real kInf = std::numeric_limits<Real>::infinity();

// Bounds of an oriented box given by centre, local half extents and rotation.
void oriented_bounds(const Vec3& c, const Vec3& half, const Mat3& rot, Vec3& lo, Vec3& hi) {
  Vec3 ext;
  for (int i = 0; i < 3; ++i)
    ext[i] = std::abs(rot.m[i][0]) * half.x + std::abs(rot.m[i][1]) * half.y +
             std::abs(rot.m[i][2]) * half.z;
  lo = c - ext;
  hi = c + ext;
}

// The vertical lines in a solid's frame: the line at (x, y) is q0 + t d there, at world height
// centre.z + t (d = rot_t (0, 0, 1), a unit vector).
struct LocalLine {
  Vec3 q0, d;
};
LocalLine local_line(Real x, Real y, const Vec3& centre, const Mat3& rot_t) {
  return {rot_t * Vec3{x - centre.x, y - centre.y, 0}, rot_t * Vec3{0, 0, 1}};
}

// Narrows [t0, t1] to the t with lo <= q + t d <= hi; false when nothing is left.
bool clip_slab(Real q, Real d, Real lo, Real hi, Real& t0, Real& t1) {
  if (d == 0) return q >= lo && q <= hi;
  Real a = (lo - q) / d, b = (hi - q) / d;
  if (a > b) std::swap(a, b);
  t0 = std::max(t0, a);
  t1 = std::min(t1, b);
  return t0 <= t1;
}

// The t with A t^2 + 2 B t + C <= 0 (A >= 0), one interval [t0, t1]; false when there are none.
// (With A = 0 the quadratic is a constant C: all t or none; A = 0 with B != 0 does not occur for
// the distances it is used for, B^2 <= A |q0|^2.)
bool within_quadric(Real a, Real b, Real c, Real& t0, Real& t1) {
  if (a <= 0) {
    t0 = -kInf;
    t1 = kInf;
    return c <= 0;
  }
  const Real disc = b * b - a * c;
  if (disc < 0) return false;
  const Real s = std::sqrt(disc);
  t0 = (-b - s) / a;
  t1 = (-b + s) / a;
  return true;
}

// The t of the line within the radial shell inner <= |q_axes| <= outer, where q_axes is q's part
// along the first `axes` (2: the distance from the z axis, 3: from the origin): one or two
// intervals, ascending, appended to ts.
void within_shell(const LocalLine& l, int axes, Real inner, Real outer,
                  std::vector<std::pair<Real, Real>>& ts) {
  Real a = 0, b = 0, c = 0;
  for (int k = 0; k < axes; ++k) {
    a += l.d[k] * l.d[k];
    b += l.q0[k] * l.d[k];
    c += l.q0[k] * l.q0[k];
  }
  Real o0, o1;
  if (!within_quadric(a, b, c - outer * outer, o0, o1)) return;
  Real i0, i1;  // the hole: inside the inner radius (its boundary belongs to the solid)
  if (inner <= 0 || !within_quadric(a, b, c - inner * inner, i0, i1) || i0 >= i1) {
    ts.push_back({o0, o1});
    return;
  }
  // (a hole of infinite ends is a line along the axis inside the inner radius: nothing is left)
  if (i0 > -kInf && o0 <= i0) ts.push_back({o0, std::min(o1, i0)});
  if (i1 < kInf && i1 <= o1) ts.push_back({std::max(o0, i1), o1});
}

// The intervals ts of a line, cut to lo <= q_z + t d_z <= hi, appended to `out` as world heights.
void append_cut(const LocalLine& l, Real centre_z, Real lo, Real hi,
                const std::vector<std::pair<Real, Real>>& ts, Stretches& out) {
  for (auto [t0, t1] : ts)
    if (clip_slab(l.q0.z, l.d.z, lo, hi, t0, t1)) out.push_back({centre_z + t0, centre_z + t1});
}
}  // namespace

void HalfSpace::bounds(Vec3& lo, Vec3& hi) const {
  lo = {-kInf, -kInf, -kInf};
  hi = {kInf, kInf, kInf};
}

void HalfSpace::vertical_stretches(Real x, Real y, Stretches& out) const {
  // dot(p - point, n) <= 0 with p = (x, y, z): z on one side of a height, or all or nothing
  const Real h = (x - point_.x) * normal_.x + (y - point_.y) * normal_.y;
  if (normal_.z == 0) {
    if (h <= 0) out.push_back({-kInf, kInf});
    return;
  }
  const Real z = point_.z - h / normal_.z;
  out.push_back(normal_.z > 0 ? std::pair{-kInf, z} : std::pair{z, kInf});
}

void RemovedSolid::vertical_stretches(Real, Real, Stretches&) const {}

SolidBox::SolidBox(const Vec3& center, const Vec3& half, const Mat3& rotation)
    : center_(center), half_(half), rot_(rotation), rot_t_(rotation.transposed()) {}

SurfacePoint SolidBox::closest(const Vec3& p) const {
  const Vec3 q = rot_t_ * (p - center_);
  const Vec3 d{std::abs(q.x) - half_.x, std::abs(q.y) - half_.y, std::abs(q.z) - half_.z};
  const Vec3 sgn{q.x < 0 ? -1.0 : 1.0, q.y < 0 ? -1.0 : 1.0, q.z < 0 ? -1.0 : 1.0};
  Vec3 n_local;
  Real dist;
  if (d.x > 0 || d.y > 0 || d.z > 0) {
    // outside: distance to the nearest point of the box (a face, an edge or a corner)
    const Vec3 out{std::max(d.x, 0.0) * sgn.x, std::max(d.y, 0.0) * sgn.y,
                   std::max(d.z, 0.0) * sgn.z};
    dist = norm(out);
    n_local = out / dist;
  } else {
    // inside: the nearest face
    int k = (d.x > d.y) ? (d.x > d.z ? 0 : 2) : (d.y > d.z ? 1 : 2);
    dist = d[k];
    n_local[k] = sgn[k];
  }
  return {dist, rot_ * n_local};
}

void SolidBox::bounds(Vec3& lo, Vec3& hi) const { oriented_bounds(center_, half_, rot_, lo, hi); }

void SolidBox::vertical_stretches(Real x, Real y, Stretches& out) const {
  const LocalLine l = local_line(x, y, center_, rot_t_);
  Real t0 = -kInf, t1 = kInf;
  for (int k = 0; k < 3; ++k)
    if (!clip_slab(l.q0[k], l.d[k], -half_[k], half_[k], t0, t1)) return;
  out.push_back({center_.z + t0, center_.z + t1});
}

SurfacePoint SolidSphere::closest(const Vec3& p) const {
  const Vec3 d = p - center_;
  const Real len = norm(d);
  const Vec3 n = len > 0 ? d / len : Vec3{0, 0, 1};
  return {len - radius_, n};
}

void SolidSphere::bounds(Vec3& lo, Vec3& hi) const {
  lo = center_ - Vec3{radius_, radius_, radius_};
  hi = center_ + Vec3{radius_, radius_, radius_};
}

void SolidSphere::vertical_stretches(Real x, Real y, Stretches& out) const {
  const Real ex = x - center_.x, ey = y - center_.y;
  const Real left = radius_ * radius_ - (ex * ex + ey * ey);
  if (left < 0) return;
  const Real s = std::sqrt(left);
  out.push_back({center_.z - s, center_.z + s});
}

SolidCylinder::SolidCylinder(const Vec3& center, Real radius, Real inner_radius, Real height,
                             const Mat3& rotation)
    : center_(center),
      radius_(radius),
      inner_radius_(inner_radius),
      half_height_(height / 2),
      rot_(rotation),
      rot_t_(rotation.transposed()) {}

SurfacePoint SolidCylinder::closest(const Vec3& p) const {
  // The cross-section in the (radial, axial) half-plane is a rectangle: [inner, outer] x [-h, h].
  const Vec3 q = rot_t_ * (p - center_);
  const Real rho = std::hypot(q.x, q.y);
  const Vec3 radial = rho > 0 ? Vec3{q.x / rho, q.y / rho, 0} : Vec3{1, 0, 0};
  // radial distance outside the wall: a solid has only its outer side, a tube both
  Real da, sa;
  if (inner_radius_ <= 0) {
    da = rho - radius_;
    sa = 1.0;
  } else {
    const Real a = rho - 0.5 * (radius_ + inner_radius_);  // from the middle of the wall
    da = std::abs(a) - 0.5 * (radius_ - inner_radius_);
    sa = a < 0 ? -1.0 : 1.0;
  }
  const Real dz = std::abs(q.z) - half_height_;
  const Real sz = q.z < 0 ? -1.0 : 1.0;
  Real dist, na, nz;
  if (da > 0 || dz > 0) {
    const Real oa = std::max(da, 0.0) * sa, oz = std::max(dz, 0.0) * sz;
    dist = std::hypot(oa, oz);
    na = oa / dist;
    nz = oz / dist;
  } else if (da > dz) {
    dist = da, na = sa, nz = 0;
  } else {
    dist = dz, na = 0, nz = sz;
  }
  const Vec3 n_local = radial * na + Vec3{0, 0, nz};
  return {dist, rot_ * n_local};
}

void SolidCylinder::bounds(Vec3& lo, Vec3& hi) const {
  oriented_bounds(center_, {radius_, radius_, half_height_}, rot_, lo, hi);
}

Real SolidCylinder::least_width() const {
  const Real across = inner_radius_ > 0 ? radius_ - inner_radius_ : 2 * radius_;
  return std::min(across, 2 * half_height_);
}

void SolidCylinder::vertical_stretches(Real x, Real y, Stretches& out) const {
  const LocalLine l = local_line(x, y, center_, rot_t_);
  std::vector<std::pair<Real, Real>> ts;
  within_shell(l, 2, inner_radius_, radius_, ts);
  append_cut(l, center_.z, -half_height_, half_height_, ts, out);
}

SolidBowl::SolidBowl(const Vec3& center, Real radius, Real thickness, Real depth,
                     const Mat3& rotation)
    : center_(center),
      inner_(radius),
      outer_(radius + thickness),
      rim_z_(depth - radius),
      rim_in_(std::sqrt(std::max(radius * radius - rim_z_ * rim_z_, 0.0))),
      rim_out_(std::sqrt(outer_ * outer_ - rim_z_ * rim_z_)),
      rot_(rotation),
      rot_t_(rotation.transposed()) {}

SurfacePoint SolidBowl::closest(const Vec3& p) const {
  // The problem is 2D in the half-plane (rho >= 0, z) through the axis and p: the section is the
  // annulus inner <= r <= outer cut by the rim line z <= rim_z. Its boundary is the inner arc,
  // the outer arc (both below the rim line) and the flat rim between (rim_in, rim_z) and
  // (rim_out, rim_z). The section is symmetric in rho, so the nearest boundary point of a point
  // with rho >= 0 has rho >= 0 too.
  const Vec3 q = rot_t_ * (p - center_);
  const Real rho = std::hypot(q.x, q.y), z = q.z;
  const Real r = std::hypot(rho, z);
  const Vec3 radial = rho > 0 ? Vec3{q.x / rho, q.y / rho, 0} : Vec3{1, 0, 0};

  // nearest point of an arc of radius a below the rim line: the radial projection when it lies
  // below the line, else the arc's end on the rim (the nearer end: the one with rho >= 0)
  struct Candidate {
    Real rho, z;      // the boundary point
    Real n_rho, n_z;  // the solid's outward normal there
  };
  const auto on_arc = [&](Real a, Real rim_rho, Real side) -> Candidate {
    const Real u_rho = r > 0 ? rho / r : 0.0, u_z = r > 0 ? z / r : -1.0;
    if (a * u_z <= rim_z_) return {a * u_rho, a * u_z, side * u_rho, side * u_z};
    return {rim_rho, rim_z_, side * rim_rho / a, side * rim_z_ / a};
  };
  const Candidate cands[3] = {
      on_arc(inner_, rim_in_, -1.0),   // the inside of the bowl: normal towards the centre
      on_arc(outer_, rim_out_, 1.0),   // the underside
      {std::clamp(rho, rim_in_, rim_out_), rim_z_, 0.0, 1.0},  // the rim
  };
  Real best = kInf;
  const Candidate* c = &cands[0];
  for (const Candidate& k : cands) {
    const Real d = std::hypot(rho - k.rho, z - k.z);
    if (d < best) best = d, c = &k;
  }
  const bool inside = r >= inner_ && r <= outer_ && z <= rim_z_;
  // the normal is the direction from the nearest point (away from it outside, towards it inside);
  // on the surface itself, the normal of the piece
  Real n_rho = c->n_rho, n_z = c->n_z;
  if (best > 1e-12 * outer_) {
    const Real s = inside ? -1.0 : 1.0;
    n_rho = s * (rho - c->rho) / best;
    n_z = s * (z - c->z) / best;
  }
  return {inside ? -best : best, rot_ * (radial * n_rho + Vec3{0, 0, n_z})};
}

void SolidBowl::bounds(Vec3& lo, Vec3& hi) const {
  // below the centre the shell reaches out to the outer radius; a rim below the centre narrows it
  const Real reach = rim_z_ >= 0 ? outer_ : rim_out_;
  const Real z_lo = -outer_, z_hi = rim_z_;
  oriented_bounds(center_ + rot_ * Vec3{0, 0, (z_lo + z_hi) / 2}, {reach, reach, (z_hi - z_lo) / 2},
                  rot_, lo, hi);
}

void SolidBowl::vertical_stretches(Real x, Real y, Stretches& out) const {
  const LocalLine l = local_line(x, y, center_, rot_t_);
  std::vector<std::pair<Real, Real>> ts;
  within_shell(l, 3, inner_, outer_, ts);
  append_cut(l, center_.z, -kInf, rim_z_, ts, out);
}

void Geometry::add(std::unique_ptr<Solid> solid, Real friction, Real rolling_friction,
                   Real twisting_friction, int source) {
  obstacles_.push_back({std::move(solid), friction, rolling_friction, twisting_friction, source});
}

void RemovedSolid::bounds(Vec3& lo, Vec3& hi) const {
  lo = {kInf, kInf, kInf};
  hi = {-kInf, -kInf, -kInf};
}

int Geometry::remove_source(int source) {
  int n = 0;
  for (Obstacle& o : obstacles_)
    if (o.source == source) {
      o.solid = std::make_unique<RemovedSolid>();
      ++n;
    }
  return n;
}

Geometry Geometry::from_config(const std::vector<GeometryConfig>& configs,
                               const MaterialConfig& material, const std::string& scene_path) {
  Geometry g;
  // what the meshes so far take: each file is bounded by its reader, all of them together by one
  // of the largest
  Real mesh_samples = 0;
  std::size_t mesh_triangles = 0;
  for (int k = 0; k < static_cast<int>(configs.size()); ++k) {
    const GeometryConfig& c = configs[k];
    const Real mu = c.friction.value_or(material.wall_friction);
    const Real mu_r = material.wall_rolling_friction, mu_tw = material.wall_twisting_friction;
    auto add = [&](std::unique_ptr<Solid> s) { g.add(std::move(s), mu, mu_r, mu_tw, k); };
    const Mat3 rot = rotation_xyz_deg(c.rotation_deg);
    switch (c.type) {
      case GeometryType::Plane:
        add(std::make_unique<HalfSpace>(c.point, c.normal / norm(c.normal)));
        break;
      case GeometryType::Sphere:
        add(std::make_unique<SolidSphere>(c.center, c.radius));
        break;
      case GeometryType::Bowl:
        add(std::make_unique<SolidBowl>(c.center, c.radius, c.wall_thickness,
                                        c.depth.value_or(c.radius), rot));
        break;
      case GeometryType::Heightmap:
        add(std::make_unique<SolidHeightmap>(c.heights, c.extent, c.base_thickness,
                                             material.largest_diameter()));
        break;
      case GeometryType::Mesh: {
        g.meshes_.push_back(place_mesh(c, material, scene_path, g.warnings_,
                                       static_cast<Real>(kMaxSurfaceSamples) - mesh_samples));
        MeshObstacle& placed = g.meshes_.back();
        placed.source = k;
        mesh_samples += placed.sample_count;
        mesh_triangles += placed.mesh.triangles.size();
        if (mesh_triangles > kMaxMeshTriangles)
          throw InputError(fmt::format(
              "{}: {}: brings the scene's meshes to {} triangles together, more than the limit "
              "of {}",
              scene_path, c.name, mesh_triangles, kMaxMeshTriangles));
        break;
      }
      case GeometryType::Box:
        if (!c.container) {
          add(std::make_unique<SolidBox>(c.center, c.size * 0.5, rot));
        } else {
          // Walls of thickness t around the inner volume `size`: floor, four sides, maybe a lid.
          const Real t = c.wall_thickness;
          const Vec3 h = c.size * 0.5;
          auto wall = [&](const Vec3& local_center, const Vec3& half) {
            add(std::make_unique<SolidBox>(c.center + rot * local_center, half, rot));
          };
          wall({0, 0, -h.z - t / 2}, {h.x + t, h.y + t, t / 2});
          if (!c.open_top) wall({0, 0, h.z + t / 2}, {h.x + t, h.y + t, t / 2});
          wall({-h.x - t / 2, 0, 0}, {t / 2, h.y + t, h.z});
          wall({h.x + t / 2, 0, 0}, {t / 2, h.y + t, h.z});
          wall({0, -h.y - t / 2, 0}, {h.x, t / 2, h.z});
          wall({0, h.y + t / 2, 0}, {h.x, t / 2, h.z});
        }
        break;
      case GeometryType::Cylinder:
        if (!c.container) {
          add(std::make_unique<SolidCylinder>(c.center, c.radius, 0.0, c.height, rot));
        } else {
          // A tube of thickness t around the inner radius, a bottom disk, maybe a lid.
          const Real t = c.wall_thickness;
          const Vec3 axis = rot * Vec3{0, 0, 1};
          add(std::make_unique<SolidCylinder>(c.center, c.radius + t, c.radius, c.height, rot));
          add(std::make_unique<SolidCylinder>(c.center - axis * (c.height / 2 + t / 2),
                                              c.radius + t, 0.0, t, rot));
          if (!c.open_top)
            add(std::make_unique<SolidCylinder>(c.center + axis * (c.height / 2 + t / 2),
                                                c.radius + t, 0.0, t, rot));
        }
        break;
    }
  }
  return g;
}

std::size_t Geometry::count_inside(const std::vector<Vec3>& x) const {
  std::vector<Vec3> outside;  // of every solid: for the meshes, tested in parallel
  std::size_t n = 0;
  for (const Vec3& p : x) {
    bool in = false;
    for (const Obstacle& o : obstacles_) in = in || o.solid->closest(p).distance < 0;
    if (in)
      ++n;
    else if (!meshes_.empty())
      outside.push_back(p);
  }
  std::vector<std::uint8_t> inside(outside.size(), 0);
  for (const MeshObstacle& m : meshes_) {
    const std::vector<Real> w = m.winding->at(outside);
    for (std::size_t i = 0; i < w.size(); ++i) inside[i] |= w[i] >= 0.5;
  }
  for (std::uint8_t f : inside) n += f;
  return n;
}

Real Geometry::top_below(Real x, Real y, Real z_from, Real z_floor) const {
  Stretches line;
  for (const Obstacle& o : obstacles_) o.solid->vertical_stretches(x, y, line);
  Real top = z_floor;
  for (const auto& [bottom, t] : line) {
    if (bottom > z_from || t <= top) continue;
    top = std::min(t, z_from);  // (z_from itself when it starts inside)
  }
  return top;
}

std::vector<std::pair<Real, Real>> Geometry::solid_intervals(Real x, Real y, Real z_from,
                                                             Real z_floor,
                                                             std::uint64_t* queries) const {
  Stretches up;
  for (const Obstacle& o : obstacles_) o.solid->vertical_stretches(x, y, up);
  // meshes: the stretches between crossings whose midpoint is inside, grown by the boundary
  // particles' radius (the grains rest on the particles)
  for (const MeshObstacle& m : meshes_) {
    const std::vector<Real> z = m.winding->vertical_crossings(x, y);
    for (std::size_t k = 0; k + 1 < z.size(); ++k)
      if (m.winding->inside({x, y, 0.5 * (z[k] + z[k + 1])}))
        up.push_back({z[k] - m.particle_radius, z[k + 1] + m.particle_radius});
  }
  if (queries) *queries += obstacles_.size() + meshes_.size();
  // their union, between z_floor and z_from; solids that touch (a container's wall standing on
  // its floor slab) meet within rounding, so a seam thinner than a nanometre is no gap
  constexpr Real kSeam = 1e-9;
  std::sort(up.begin(), up.end());
  std::vector<std::pair<Real, Real>> merged;
  for (const auto& iv : up) {
    if (iv.second < z_floor || iv.first > z_from) continue;
    if (!merged.empty() && iv.first <= merged.back().second + kSeam)
      merged.back().second = std::max(merged.back().second, iv.second);
    else
      merged.push_back(iv);
  }
  for (auto& [bottom, top] : merged) {
    if (bottom <= z_floor) bottom = -kInf;
    top = std::min(top, z_from);
  }
  return merged;
}

bool Geometry::finite_bounds(Vec3& lo, Vec3& hi) const {
  bool any = false;
  for (const Obstacle& o : obstacles_) {
    Vec3 a, b;
    o.solid->bounds(a, b);
    if (!is_finite(a) || !is_finite(b)) continue;
    lo = any ? min(lo, a) : a;
    hi = any ? max(hi, b) : b;
    any = true;
  }
  for (const MeshObstacle& m : meshes_) {
    const Aabb box = mesh_bounds(m.mesh);
    if (box.empty()) continue;
    const Vec3 pad{m.particle_radius, m.particle_radius, m.particle_radius};
    lo = any ? min(lo, box.lo - pad) : box.lo - pad;
    hi = any ? max(hi, box.hi + pad) : box.hi + pad;
    any = true;
  }
  return any;
}

}  // namespace sandflow

#include "geometry/mesh_sampling.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include <fmt/format.h>

#include "core/error.hpp"

namespace sandflow {

namespace {

// Subdivisions of a triangle's edges so that the copies' edges are at most `spacing`: in floating
// point, since a huge mesh needs more than any integer holds (check_sample_count refuses it).
Real subdivisions(const Vec3& a, const Vec3& b, const Vec3& c, Real spacing) {
  const Real longest = std::sqrt(std::max({norm2(b - a), norm2(c - b), norm2(a - c)}));
  return std::max(1.0, std::ceil(longest / spacing));
}

// Points kept so far, hashed by cells of the merge tolerance, to drop near copies.
class MergeGrid {
 public:
  explicit MergeGrid(Real tolerance) : tol_(tolerance), tol2_(tolerance * tolerance) {}

  // Keeps p unless a kept point lies within the tolerance.
  void add(const Vec3& p, std::vector<Vec3>& kept) {
    const std::int64_t cx = cell(p.x), cy = cell(p.y), cz = cell(p.z);
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dz = -1; dz <= 1; ++dz)
          if (near_one_in(key(cx + dx, cy + dy, cz + dz), p, kept)) return;
    const std::uint64_t k = key(cx, cy, cz);
    const auto it = head_.find(k);
    next_.push_back(it == head_.end() ? kNone : it->second);
    head_[k] = static_cast<std::uint32_t>(kept.size());
    kept.push_back(p);
  }

 private:
  static constexpr std::uint32_t kNone = 0xffffffffu;

  std::int64_t cell(Real v) const { return static_cast<std::int64_t>(std::floor(v / tol_)); }
  // Cells that share a key share a chain: correct (distances are checked), only slower.
  static std::uint64_t key(std::int64_t x, std::int64_t y, std::int64_t z) {
    return static_cast<std::uint64_t>(x) * 0x9e3779b97f4a7c15ULL ^
           static_cast<std::uint64_t>(y) * 0xc2b2ae3d27d4eb4fULL ^
           static_cast<std::uint64_t>(z) * 0x165667b19e3779f9ULL;
  }
  bool near_one_in(std::uint64_t k, const Vec3& p, const std::vector<Vec3>& kept) const {
    const auto it = head_.find(k);
    if (it == head_.end()) return false;
    for (std::uint32_t i = it->second; i != kNone; i = next_[i])
      if (norm2(kept[i] - p) <= tol2_) return true;
    return false;
  }

  Real tol_, tol2_;
  std::unordered_map<std::uint64_t, std::uint32_t> head_;  ///< cell key -> last kept point
  std::vector<std::uint32_t> next_;                        ///< kept point -> previous in its cell
};

}  // namespace

Real check_surface_sample_count(const TriangleMesh& mesh, Real spacing, Real budget) {
  Real total = 0;
  for (const auto& t : mesh.triangles) {
    const Real n = subdivisions(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]], spacing);
    total += (n + 1) * (n + 2) / 2;
  }
  // (a total past any integer, or not finite, is refused as well)
  if (!(total <= budget))
    throw InputError(fmt::format(
        "sampling the mesh at spacing {:.4g} m needs about {:.3g} boundary particles, more than "
        "{} (a smaller scale or size, larger grains or particle_radius, or a coarser mesh)",
        spacing, total,
        budget >= static_cast<Real>(kMaxSurfaceSamples)
            ? fmt::format("the limit of {}", kMaxSurfaceSamples)
            : fmt::format("the {:.0f} left of the limit of {} for all of the scene's meshes",
                          std::max<Real>(budget, 0), kMaxSurfaceSamples)));
  return total;
}

std::vector<Vec3> sample_surface(const TriangleMesh& mesh, Real spacing, Real merge) {
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw std::invalid_argument("sample_surface: spacing must be positive and finite");
  check_surface_sample_count(mesh, spacing);
  std::vector<Vec3> samples;
  MergeGrid grid(merge > 0 ? merge : spacing / 8);
  for (const auto& t : mesh.triangles) {
    const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    // (at most kMaxSurfaceSamples, checked above: the cast is exact)
    const auto n = static_cast<std::uint64_t>(subdivisions(a, b, c, spacing));
    // the corners of the n^2 copies: a + (b - a) i / n + (c - a) j / n, i + j <= n
    for (std::uint64_t i = 0; i <= n; ++i)
      for (std::uint64_t j = 0; i + j <= n; ++j) {
        const Real u = static_cast<Real>(i) / static_cast<Real>(n);
        const Real v = static_cast<Real>(j) / static_cast<Real>(n);
        grid.add(a + (b - a) * u + (c - a) * v, samples);
      }
  }
  return samples;
}

}  // namespace sandflow

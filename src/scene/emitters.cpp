#include "scene/emitters.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/error.hpp"

namespace sandflow {

Emitter::Emitter(const EmitterConfig& config, const MaterialConfig& material, const Vec3& gravity,
                 const std::string& where)
    : config_(config), material_(material) {
  d_max_ = material.diameter * (1 + material.diameter_spread);
  spacing_ = config.spacing * d_max_;
  const Real s = spacing_;

  if (config.type == EmitterType::Pour) {
    // one layer of slots on a hexagonal pattern inside the disk or rectangle
    const Real hx = config.shape == PourShape::Disk ? config.radius : config.size.x / 2;
    const Real hy = config.shape == PourShape::Disk ? config.radius : config.size.y / 2;
    const Real row = s * std::sqrt(3.0) / 2;
    int k = 0;
    for (Real y = -hy + d_max_ / 2; y <= hy - d_max_ / 2 + 1e-12; y += row, ++k) {
      for (Real x = -hx + d_max_ / 2 + (k % 2) * s / 2; x <= hx - d_max_ / 2 + 1e-12; x += s) {
        if (config.shape == PourShape::Disk &&
            std::hypot(x, y) > config.radius - d_max_ / 2 + 1e-12)
          continue;
        slots_.push_back(config.center + Vec3{x, y, 0});
      }
    }
    if (slots_.empty())
      throw InputError(fmt::format("{}: the pour area is smaller than one grain", where));
    // the next batch waits until the previous one has fallen one spacing: v0 t + g t^2 / 2 = s
    const Real g = norm(gravity);
    const Real v0 =
        g > 0 ? std::max(0.0, dot(config.velocity, gravity) / g) : norm(config.velocity);
    if (g <= 0 && v0 <= 0)
      throw InputError(fmt::format(
          "{}: a pour needs gravity or an initial velocity to carry grains away", where));
    batch_interval_ = g > 0 ? (-v0 + std::sqrt(v0 * v0 + 2 * g * s)) / g : s / v0;
    per_batch_ = config.rate * batch_interval_;
    const Real max_rate = static_cast<Real>(slots_.size()) / batch_interval_;
    if (per_batch_ > static_cast<Real>(slots_.size()))
      throw InputError(fmt::format(
          "{}: rate {} grains/s is more than this pour can emit without overlaps ({:.0f} "
          "grains/s); enlarge the pour area or its downward speed",
          where, config.rate, max_rate));
  } else {
    // fill the box with a lattice: cubic for a block, face-centred cubic for a prefilled pile
    const Vec3 half = config.size * 0.5;
    const Vec3 lo = config.center - half + Vec3{d_max_, d_max_, d_max_} * 0.5;
    const Vec3 hi = config.center + half - Vec3{d_max_, d_max_, d_max_} * 0.5;
    const bool fcc = config.type == EmitterType::Lattice;
    const Real a = fcc ? s * std::sqrt(2.0) : s;  // FCC cube edge: nearest neighbours at s
    const Vec3 basis_fcc[4] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
    const int nb = fcc ? 4 : 1;
    for (Real z = lo.z; z <= hi.z + 1e-12; z += a)
      for (Real y = lo.y; y <= hi.y + 1e-12; y += a)
        for (Real x = lo.x; x <= hi.x + 1e-12; x += a)
          for (int b = 0; b < nb; ++b) {
            const Vec3 p = Vec3{x, y, z} + basis_fcc[b] * a;
            if (p.x <= hi.x + 1e-12 && p.y <= hi.y + 1e-12 && p.z <= hi.z + 1e-12 &&
                static_cast<std::int64_t>(slots_.size()) < config.count)
              slots_.push_back(p);
          }
    if (static_cast<std::int64_t>(slots_.size()) < config.count)
      throw InputError(fmt::format(
          "{}: the box holds only {} grains at spacing {}, fewer than count = {}; enlarge size",
          where, slots_.size(), config.spacing, config.count));
  }
  next_time_ = config.start;
  // a new grain's surface reaches its slot plus the jitter plus its radius
  reach_ = config.jitter * std::max(0.0, spacing_ - d_max_) / 2 + d_max_ / 2;
  slot_lo_ = slot_hi_ = slots_.front();
  for (const Vec3& p : slots_) {
    slot_lo_ = min(slot_lo_, p);
    slot_hi_ = max(slot_hi_, p);
  }
}

bool Emitter::near_slots(const Vec3& x, Real r) const {
  const Real m = reach_ + r;
  return x.x > slot_lo_.x - m && x.x < slot_hi_.x + m && x.y > slot_lo_.y - m &&
         x.y < slot_hi_.y + m && x.z > slot_lo_.z - m && x.z < slot_hi_.z + m;
}

Real Emitter::end_time() const {
  if (config_.type != EmitterType::Pour) return config_.start;
  const Real batches = std::ceil(static_cast<Real>(config_.count) / per_batch_);
  return config_.start + (batches - 1) * batch_interval_;
}

Real Emitter::draw_radius(Rng& rng) const {
  const Real spread = material_.diameter_spread;
  return 0.5 * material_.diameter * (1 + spread * rng.uniform(-1.0, 1.0));
}

void Emitter::emit(Real t, Rng& rng, std::vector<NewGrain>& out, const std::vector<Vec3>& nearby_x,
                   const std::vector<Real>& nearby_r) {
  if (done() || t < next_time_) return;
  // Jitter moves a grain by at most half the free gap, so new grains never overlap.
  const Real gap = std::max(0.0, spacing_ - d_max_);
  const Real jit = config_.jitter * gap / 2;
  auto jittered = [&](const Vec3& p) {
    return p + Vec3{rng.uniform(-jit, jit), rng.uniform(-jit, jit), rng.uniform(-jit, jit)} *
                   (1.0 / std::sqrt(3.0));
  };

  if (config_.type != EmitterType::Pour) {
    for (const Vec3& p : slots_) out.push_back({jittered(p), config_.velocity, draw_radius(rng)});
    emitted_ = config_.count;
    return;
  }
  // pour: a batch of randomly chosen free slots
  owed_ += per_batch_;
  auto k = static_cast<std::int64_t>(owed_);
  k = std::min<std::int64_t>(
      {k, config_.count - emitted_, static_cast<std::int64_t>(slots_.size())});
  owed_ -= static_cast<Real>(k);
  std::vector<std::uint32_t> order(slots_.size());
  for (std::uint32_t q = 0; q < order.size(); ++q) order[q] = q;
  // a slot is taken when a grain already there (the top of a heap grown up to the pour, or a
  // grain thrown back up) would overlap a new grain at it: placing one there would fire both off
  auto occupied = [&](const Vec3& slot) {
    for (std::size_t g = 0; g < nearby_x.size(); ++g) {
      const Real reach = reach_ + nearby_r[g];
      if (norm2(nearby_x[g] - slot) < reach * reach) return true;
    }
    return false;
  };
  std::int64_t placed = 0;
  for (std::size_t q = 0; q < order.size() && placed < k; ++q) {  // partial Fisher-Yates
    const auto pick =
        q + static_cast<std::size_t>(rng.uniform() * static_cast<Real>(order.size() - q));
    std::swap(order[q], order[std::min(pick, order.size() - 1)]);
    if (occupied(slots_[order[q]])) continue;
    out.push_back({jittered(slots_[order[q]]), config_.velocity, draw_radius(rng)});
    ++placed;
  }
  owed_ += static_cast<Real>(k - placed);  // the grains of taken slots come with later batches
  delayed_ += k - placed;
  emitted_ += placed;
  next_time_ += batch_interval_;
}

}  // namespace sandflow

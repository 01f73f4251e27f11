#include "sim/emitters.hpp"

#include <algorithm>
#include <cmath>
#include <compare>
#include <limits>
#include <numbers>
#include <optional>
#include <tuple>

#include <fmt/format.h>

#include "config/emitter_region.hpp"
#include "core/error.hpp"
#include "core/threads.hpp"
#include "geometry/heightmap.hpp"

namespace sandflow {

namespace {

// Half extents of the area a pour places grains over (x, y) or of a block's box.
Vec3 half_extent(const EmitterConfig& e) {
  if (e.type == EmitterType::Bed) return {e.size.x / 2, e.size.y / 2, 0};
  if (e.type != EmitterType::Pour) return e.size * 0.5;
  if (e.shape == PourShape::Disk) return {e.radius, e.radius, 0};
  return {e.size.x / 2, e.size.y / 2, 0};
}

// The grains already near an emitter (centres and radii), filed in cubic cells so that a block or
// a bed of a million new grains tests each one against the few old grains near it.
class Occupancy {
 public:
  // reach: the largest distance of a new grain's surface from its place that will be asked about
  Occupancy(const std::vector<Vec3>& x, const std::vector<Real>& r, Real reach) : x_(x), r_(r) {
    if (x.empty()) return;
    cell_ = reach + *std::max_element(r.begin(), r.end());
    cells_.reserve(x.size());
    for (std::size_t g = 0; g < x.size(); ++g) {
      const auto [i, j, k] = cell_of(x[g]);
      cells_.push_back({i, j, k, static_cast<std::uint32_t>(g)});
    }
    std::sort(cells_.begin(), cells_.end());
  }

  // True when a new grain whose surface reaches `reach` from p (at most the constructor's) would
  // overlap an old one.
  bool taken(const Vec3& p, Real reach) const {
    if (cells_.empty()) return false;
    const auto [i, j, k] = cell_of(p);
    for (std::int64_t c = k - 1; c <= k + 1; ++c)
      for (std::int64_t b = j - 1; b <= j + 1; ++b)
        for (std::int64_t a = i - 1; a <= i + 1; ++a) {
          const Entry lo{a, b, c, 0};
          for (auto e = std::lower_bound(cells_.begin(), cells_.end(), lo);
               e != cells_.end() && e->i == a && e->j == b && e->k == c; ++e) {
            const Real touch = reach + r_[e->grain];
            if (norm2(x_[e->grain] - p) < touch * touch) return true;
          }
        }
    return false;
  }

 private:
  struct Entry {
    std::int64_t i, j, k;
    std::uint32_t grain;
    auto operator<=>(const Entry&) const = default;
  };
  std::tuple<std::int64_t, std::int64_t, std::int64_t> cell_of(const Vec3& p) const {
    return {static_cast<std::int64_t>(std::floor(p.x / cell_)),
            static_cast<std::int64_t>(std::floor(p.y / cell_)),
            static_cast<std::int64_t>(std::floor(p.z / cell_))};
  }

  const std::vector<Vec3>& x_;
  const std::vector<Real>& r_;
  Real cell_ = 0;
  std::vector<Entry> cells_;  // sorted by cell, then grain
};

/// Most slot pairs stream_is_clear tests (a fraction of a second); a pour that would need more
/// falls as discs.
constexpr double kMaxStreamPairs = 2e7;
/// A pour whose slots cannot lead by an eighth of a batch interval falls as discs: less would
/// hardly break them up.
constexpr Real kLeastStreamLead = 1.0 / 8;

// Whether grains that leave slot q lead[q] early (each lead less than the batch interval T) never
// come closer than `clearance`, centre to centre, while they fall: nullopt when there are more
// pairs to test than kMaxStreamPairs. Gravity g is across the slots' plane and v does not rise
// against it. The older A of two grains in flight has fallen df longer than the younger B; at B's
// birth they are S = (a - b) + v df + g df (l_B + df / 2) apart, and a time t later S + g df t:
// the closest they come is |S|, or S's part across g when A is still above B. A pair df >= T
// apart has fallen at least a slot spacing further along g and only parts, so the pairs tested
// are those of one batch and of neighbouring batches, of slots nearer than clearance plus what v
// carries across g in T.
std::optional<bool> stream_is_clear(const std::vector<Vec3>& slots, const std::vector<Real>& lead,
                                    Real T, const Vec3& v, const Vec3& g, Real spacing,
                                    Real clearance) {
  const Vec3 down = g * (1 / norm(g));
  const Vec3 across = v - down * dot(v, down);
  if (norm2(across) == 0 && spacing >= clearance) return true;  // apart by a spacing across g
  const Real reach = clearance + norm(across) * T;
  const double per_slot = 9 * reach * reach / (spacing * spacing * std::sqrt(3.0) / 2);
  if (per_slot * static_cast<double>(slots.size()) / 2 > kMaxStreamPairs) return std::nullopt;
  struct Entry {
    std::int64_t i, j;
    std::uint32_t slot;
    auto operator<=>(const Entry&) const = default;
  };
  auto cell = [&](const Vec3& p) {
    return std::pair{static_cast<std::int64_t>(std::floor(p.x / reach)),
                     static_cast<std::int64_t>(std::floor(p.y / reach))};
  };
  std::vector<Entry> cells;
  cells.reserve(slots.size());
  for (std::uint32_t q = 0; q < slots.size(); ++q) {
    const auto [i, j] = cell(slots[q]);
    cells.push_back({i, j, q});
  }
  std::sort(cells.begin(), cells.end());
  auto apart = [&](std::uint32_t older, std::uint32_t younger, Real df) {
    const Vec3 s = slots[older] - slots[younger] + v * df + g * (df * (lead[younger] + df / 2));
    const Real below = dot(s, down);  // > 0: the older one is below, and they part
    const Real closest2 = below >= 0 ? norm2(s) : norm2(s) - below * below;
    return closest2 >= clearance * clearance;
  };
  for (std::uint32_t q = 0; q < slots.size(); ++q) {
    const auto [i, j] = cell(slots[q]);
    for (std::int64_t b = j - 1; b <= j + 1; ++b)
      for (std::int64_t a = i - 1; a <= i + 1; ++a)
        for (auto e = std::lower_bound(cells.begin(), cells.end(), Entry{a, b, 0});
             e != cells.end() && e->i == a && e->j == b; ++e) {
          const std::uint32_t p = e->slot;
          if (p <= q) continue;
          const Real d = lead[p] - lead[q];  // one batch: the larger lead is the older grain
          if (!(d >= 0 ? apart(p, q, d) : apart(q, p, -d))) return false;
          // neighbouring batches: the earlier batch's grain is older by T less the lead it lacks
          if (d < 0 && !apart(p, q, T + d)) return false;
          if (d > 0 && !apart(q, p, T - d)) return false;
        }
  }
  return true;
}

// A pour's slots: one layer on a hexagonal pattern of spacing s inside its disk or rectangle (at
// most kMaxPourSlots, and each step of x and y moves them: emitter_problem saw to both), level or
// across its velocity (pour_axes).
std::vector<Vec3> pour_slot_centres(const EmitterConfig& config, Real d_max, Real s) {
  std::vector<Vec3> slots;
  const Vec3 half = half_extent(config);
  const PourAxes axes = pour_axes(config);
  const Real row = s * std::sqrt(3.0) / 2;
  int k = 0;
  for (Real y = -half.y + d_max / 2; y <= half.y - d_max / 2 + 1e-12; y += row, ++k) {
    for (Real x = -half.x + d_max / 2 + (k % 2) * s / 2; x <= half.x - d_max / 2 + 1e-12; x += s) {
      if (config.shape == PourShape::Disk && std::hypot(x, y) > config.radius - d_max / 2 + 1e-12)
        continue;
      slots.push_back(config.center + axes.along * x + axes.across * y);
    }
  }
  return slots;
}

// The time between a pour's batches: the next waits until the previous one has gone one spacing
// from the area, u t + a t^2 / 2 = s: a level area's batch falls it (u, a: the speed and gravity
// along gravity, u at least 0), a nozzle's flies it along its aim n (u = |v|, a = g.n, which may
// be against it), and without gravity either flies it. NaN when a nozzle's grains stop before
// (thrown up too slowly to clear their own nozzle).
Real pour_batch_interval(const EmitterConfig& config, const Vec3& gravity, Real s) {
  const Vec3& velocity = config.velocity;
  const Real g = norm(gravity);
  Real u = 0, a = 0;
  if (config.facing == PourFacing::Velocity) {
    u = norm(velocity);
    a = u > 0 ? dot(gravity, velocity) / u : 0;
  } else {
    u = g > 0 ? std::max(0.0, dot(velocity, gravity) / g) : norm(velocity);
    a = g;
  }
  if (a == 0) return s / u;
  const Real disc = u * u + 2 * a * s;
  if (disc < 0) return std::numeric_limits<Real>::quiet_NaN();
  return (-u + std::sqrt(disc)) / a;  // (the first root: with a < 0 both are positive)
}

// Whether a level pour falls along z and is not thrown up into its own stream: only such a pour
// needs its slots to lead to fall as a stream (stream_leads). A nozzle's batches leave one behind
// the other along its aim: a stream without leads.
bool pour_falls(const EmitterConfig& config, const Vec3& gravity) {
  return config.facing == PourFacing::Up && norm(gravity) > 0 && gravity.x == 0 && gravity.y == 0 &&
         dot(config.velocity, gravity) >= 0;
}

// How early each of a pour's slots lets its grains go (see stream_leads).
struct StreamLeads {
  std::vector<Real> lead;  // per slot [s]
  Real part = 0;           // the largest lead, in batch intervals (0: it falls as discs)
  bool checked = true;     // false: too many slot pairs to test, so it falls as discs
};

// A stream, not a stack of discs: each slot's grains leave as if born up to one interval (T)
// before their batch, a fixed share of it for each slot, so neighbouring slots' grains fall at
// different heights. Their paths are still free fall from the pour (the same speeds where they
// land), and one slot's grains are still one interval apart. Straight down, slots a spacing s
// apart across stay so: nothing overlaps. Thrown sideways, a slot's grains cross its neighbours'
// paths, so the leads shrink (by halves) until stream_is_clear finds every pair clear (jitter
// included), or the pour falls as discs, which never meet.
StreamLeads stream_leads(const EmitterConfig& config, const std::vector<Vec3>& slots, Real T,
                         const Vec3& gravity, Real d_max, Real s) {
  StreamLeads out;
  out.lead.assign(slots.size(), 0);
  Rng shares(0x5eed57ea3ULL);  // (the same stream for every seed: the emitter's, not the run's)
  std::vector<Real> share(slots.size());
  for (Real& u : share) u = shares.uniform();
  const bool falls = pour_falls(config, gravity);
  const Real clearance = d_max + config.jitter * std::max(0.0, s - d_max);
  for (Real part = 1; falls && part >= kLeastStreamLead; part /= 2) {
    for (std::size_t q = 0; q < slots.size(); ++q) out.lead[q] = part * share[q] * T;
    const std::optional<bool> clear =
        stream_is_clear(slots, out.lead, T, config.velocity, gravity, s, clearance);
    if (clear == true) {
      out.part = part;
      return out;
    }
    out.lead.assign(slots.size(), 0);
    if (!clear) {
      out.checked = false;
      return out;
    }
  }
  return out;
}

// What a level pour thrown sideways or up is told it could be instead.
constexpr const char* kNozzleAdvice =
    "; facing = \"velocity\" turns its area across its throw (a nozzle), whose batches leave "
    "one behind the other along it as a stream";

// The spacings a pour that cannot stream is tried at, for the one to suggest (in diameters).
constexpr Real kStreamSpacings[] = {1.1, 1.2, 1.3, 1.4, 1.5, 1.75, 2.0, 2.5, 3.0};

// What a pour thrown sideways that cannot fall as a whole stream (its slots lead by `part` of a
// batch interval at most; `checked`: its slot pairs were few enough to test) says at the start
// of a run, with the smallest wider spacing that would let it, and whether that spacing holds its
// rate. Its grains would meet in flight as a stream: the wider spacing leaves room between their
// paths.
std::string broken_stream_warning(const EmitterConfig& config, const MaterialConfig& material,
                                  const Vec3& gravity, const std::string& where, Real part,
                                  bool checked) {
  const Real d_max = material.largest_diameter();
  const Vec3 down = gravity * (1 / norm(gravity));
  const Real speed = norm(config.velocity);
  const Real off_vertical =
      speed > 0 ? std::acos(std::clamp(dot(config.velocity, down) / speed, -1.0, 1.0)) * 180 /
                      std::numbers::pi
                : 0;
  const std::string how =
      part > 0 ? fmt::format(
                     "its grains leave at most {} of a batch interval early, so it falls in "
                     "layers",
                     part == 0.5 ? "half" : fmt::format("{:g}", part))
               : "it falls as discs (each batch a layer of grains)";
  const std::string head = fmt::format(
      "{}: thrown {:.0f} degrees off the vertical, this pour's grains would meet in "
      "flight as a stream at spacing = {:g}, so {}",
      where, off_vertical, config.spacing, how);
  if (!checked)
    return head + " (its slots are too many to check each pair's paths)" + kNozzleAdvice;
  for (const Real spacing : kStreamSpacings) {
    if (spacing <= config.spacing) continue;
    EmitterConfig wider = config;
    wider.spacing = spacing;
    const Real s = spacing * d_max;
    const std::vector<Vec3> slots = pour_slot_centres(wider, d_max, s);
    if (slots.empty()) break;
    const Real T = pour_batch_interval(config, gravity, s);
    const StreamLeads wide = stream_leads(wider, slots, T, gravity, d_max, s);
    if (!wide.checked) break;
    if (wide.part < 1) continue;
    const Real max_rate = static_cast<Real>(slots.size()) / T;
    return head +
           (config.rate <= max_rate
                ? fmt::format("; spacing = {:g} lets it fall as a stream", spacing)
                : fmt::format("; spacing = {:g} lets it fall as a stream, at up to {:.0f} "
                              "grains/s from this area: {:.3g} times the area for its "
                              "{:.6g} grains/s",
                              spacing, max_rate, config.rate / max_rate, config.rate)) +
           kNozzleAdvice;
  }
  return head +
         fmt::format(
             "; no spacing up to {:g} lets it fall as a stream: throw it closer to the "
             "vertical",
             std::end(kStreamSpacings)[-1]) +
         kNozzleAdvice;
}

}  // namespace

Real pour_slots(const EmitterConfig& e, const MaterialConfig& m) {
  if (e.type != EmitterType::Pour) return 0;
  // the pattern's rows and columns over the area's bounding rectangle
  const Real d = m.largest_diameter();
  const Real s = e.spacing * d;
  const Vec3 half = half_extent(e);
  const Real row = s * std::sqrt(3.0) / 2;
  const Real rows = std::floor(std::max(0.0, 2 * half.y - d) / row) + 1;
  const Real cols = std::floor(std::max(0.0, 2 * half.x - d) / s) + 1;
  return rows * cols * (e.shape == PourShape::Disk ? std::numbers::pi / 4 : 1.0);
}

namespace {

// The lattice of a block (cubic) or a lattice emitter (face-centred cubic): points
// lo + (i + offset) a along each axis, i = 0, 1, ..., from the box's low corner a grain's radius
// in, up to a grain's radius from its high side; FCC adds three points offset by half an edge.
struct BoxLattice {
  Real a;                   // edge [m]
  Vec3 lo;                  // first point [m]
  int basis;                // points per cell: 1 or 4
  std::int64_t rows[4][3];  // per basis point, rows along x, y, z
  static constexpr Real kOffset[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
};

BoxLattice box_lattice(const EmitterConfig& e, Real d_max) {
  BoxLattice L{};
  const bool fcc = e.type == EmitterType::Lattice;
  L.a = e.spacing * d_max * (fcc ? std::sqrt(2.0) : 1.0);  // FCC edge: neighbours at spacing
  L.basis = fcc ? 4 : 1;
  L.lo = e.center - e.size * 0.5 + Vec3{d_max, d_max, d_max} * 0.5;
  const Real side[3] = {e.size.x, e.size.y, e.size.z};
  for (int b = 0; b < L.basis; ++b)
    for (int k = 0; k < 3; ++k) {
      // the box takes a grain 1e-12 m too wide (emitter_problem): a row that fits exactly counts
      const Real span = (side[k] - d_max + 1e-12) / L.a - BoxLattice::kOffset[b][k];
      L.rows[b][k] = span < 0 ? 0 : static_cast<std::int64_t>(std::floor(span)) + 1;
    }
  return L;
}

}  // namespace

Real box_slots(const EmitterConfig& e, const MaterialConfig& m) {
  if (e.type == EmitterType::Pour || e.type == EmitterType::Bed) return 0;
  const BoxLattice L = box_lattice(e, m.largest_diameter());
  Real n = 0;
  for (int b = 0; b < L.basis; ++b)
    n += static_cast<Real>(L.rows[b][0]) * static_cast<Real>(L.rows[b][1]) *
         static_cast<Real>(L.rows[b][2]);
  return n;
}

std::optional<EmitterProblem> emitter_problem(const EmitterConfig& e, const MaterialConfig& m) {
  const Real d = m.largest_diameter();
  const Real s = e.spacing * d;
  const Vec3 half = half_extent(e);
  const char* size_key = e.type == EmitterType::Pour && e.shape == PourShape::Disk ? "radius" : "size";

  const Real far_centre = std::max({std::abs(e.center.x), std::abs(e.center.y), std::abs(e.center.z)});
  const Real far_half = std::max({half.x, half.y, half.z});
  const Real reach = s * kMaxSpacingsFromOrigin;
  if (!(far_centre + far_half <= reach))
    return EmitterProblem{
        far_centre >= far_half ? "center" : size_key,
        fmt::format("reaches {:.3g} m from the origin: slots {:.3g} m apart are placed exactly only "
                    "within {:.3g} m of it (2^40 spacings)",
                    far_centre + far_half, s, reach)};

  if (e.type == EmitterType::Pour) {
    const Real slots = pour_slots(e, m);
    if (slots > kMaxPourSlots)
      return EmitterProblem{
          size_key, fmt::format("makes a pour of about {:.3g} slots {:.3g} m apart, more than the "
                                "limit of {:.0f}; make the pour smaller or the grains larger",
                                slots, s, kMaxPourSlots)};
    return std::nullopt;
  }
  const char* axis[3] = {"x", "y", "z"};
  const Real sides[3] = {e.size.x, e.size.y, e.size.z};
  for (int k = 0; k < (e.type == EmitterType::Bed ? 2 : 3); ++k)
    if (sides[k] < d - 2e-12)  // the lattice takes a grain 1e-12 m too wide
      return EmitterProblem{
          "size", fmt::format("is {:.3g} m along {}, less than the largest grain ({:.3g} m): the "
                              "box holds no grain",
                              sides[k], axis[k], d)};
  return std::nullopt;
}

template <class F>
std::int64_t Emitter::for_each_box_slot(F&& f) const {
  // layer by layer from the bottom; every row holds at least its first point (emitter_problem:
  // the box is a grain wide), so this ends by `count`
  const BoxLattice L = box_lattice(config_, d_max_);
  std::int64_t n = 0;
  if (config_.count <= 0) return n;
  const std::int64_t* base = L.rows[0];  // the corner points have the most rows
  for (std::int64_t k = 0; k < base[2]; ++k)
    for (std::int64_t j = 0; j < base[1]; ++j)
      for (std::int64_t i = 0; i < base[0]; ++i)
        for (int b = 0; b < L.basis; ++b) {
          const Real* o = BoxLattice::kOffset[b];
          if (i >= L.rows[b][0] || j >= L.rows[b][1] || k >= L.rows[b][2]) continue;
          f(L.lo + Vec3{(static_cast<Real>(i) + o[0]) * L.a, (static_cast<Real>(j) + o[1]) * L.a,
                        (static_cast<Real>(k) + o[2]) * L.a});
          if (++n == config_.count) return n;
        }
  return n;
}

Emitter::Emitter(const EmitterConfig& config, const MaterialConfig& material, const Vec3& gravity,
                 const std::string& where)
    : config_(config), material_(material) {
  if (const auto problem = emitter_problem(config, material))
    throw InputError(fmt::format("{}.{} {}", where, problem->key, problem->what));
  d_max_ = material.largest_diameter();
  spacing_ = config.spacing * d_max_;
  const Real s = spacing_;
  // a new grain's surface reaches its slot plus the jitter plus its radius
  reach_ = config.jitter * std::max(0.0, spacing_ - d_max_) / 2 + d_max_ / 2;
  next_time_ = config.start;
  gravity_ = gravity;

  if (config.type == EmitterType::Pour) {
    slots_ = pour_slot_centres(config, d_max_, s);
    if (slots_.empty())
      throw InputError(fmt::format("{}: the pour area is smaller than one grain", where));
    const Real g = norm(gravity);
    if (g <= 0 && norm(config.velocity) <= 0)
      throw InputError(fmt::format(
          "{}: a pour needs gravity or an initial velocity to carry grains away", where));
    const bool nozzle = config.facing == PourFacing::Velocity;
    if (nozzle && norm(config.velocity) <= 0)
      throw InputError(fmt::format(
          "{}: a pour facing its velocity needs a velocity (its area lies across it)", where));
    batch_interval_ = pour_batch_interval(config, gravity, s);
    if (!std::isfinite(batch_interval_))
      throw InputError(fmt::format(
          "{}: thrown at {:.4g} m/s against gravity's {:.4g} m/s^2 along its aim, this nozzle's "
          "grains stop within one spacing ({:.4g} m) of it and would meet the next batch there; "
          "throw it at least {:.4g} m/s or aim it lower",
          where, norm(config.velocity), -dot(gravity, config.velocity) / norm(config.velocity), s,
          std::sqrt(-2 * s * dot(gravity, config.velocity) / norm(config.velocity))));
    per_batch_ = config.rate * batch_interval_;
    const Real max_rate = static_cast<Real>(slots_.size()) / batch_interval_;
    if (per_batch_ > static_cast<Real>(slots_.size()))
      throw InputError(fmt::format(
          "{}: rate {:.6g} grains/s{} is more than this pour can emit without overlaps ({:.0f} "
          "grains/s); enlarge the pour area or its {}speed{}",
          where, config.rate,
          config.rate_scale != 1
              ? fmt::format(" (the scene's {:.6g} scaled with the count by --grains, which keeps "
                            "a pour's duration)",
                            config.rate / config.rate_scale)
              : "",
          max_rate, nozzle ? "" : "downward ",
          config.rate_scale != 1 ? ", or ask for fewer grains" : ""));
    StreamLeads leads = stream_leads(config, slots_, batch_interval_, gravity, d_max_, s);
    slot_lead_ = std::move(leads.lead);
    stream_lead_ = leads.part;
    stream_checked_ = leads.checked;
    where_ = where;
    // a batch is born at the first step past its wait, and a slot leads by up to an interval:
    // bound the fall over two
    const Real wait = 2 * batch_interval_;
    drop_ = norm(config.velocity) * wait + g * wait * wait / 2;
    slot_lo_ = slot_hi_ = slots_.front();
    for (const Vec3& p : slots_) {
      slot_lo_ = min(slot_lo_, p);
      slot_hi_ = max(slot_hi_, p);
    }
    return;
  }
  if (config.type == EmitterType::Bed) return;  // (its grains come with set_bed)
  // a block or lattice: its grains are counted here and placed when emitted
  bool first = true;
  const std::int64_t fits = for_each_box_slot([&](const Vec3& p) {
    slot_lo_ = first ? p : min(slot_lo_, p);
    slot_hi_ = first ? p : max(slot_hi_, p);
    first = false;
  });
  if (fits < config.count)
    throw InputError(fmt::format(
        "{}: the box holds only {} grains at spacing {}, fewer than count = {}; enlarge size",
        where, fits, config.spacing, config.count));
}

void Emitter::set_bed(BedPacking bed, const std::string& where) {
  if (static_cast<std::int64_t>(bed.size()) != config_.count)
    throw InputError(fmt::format(
        "{}: the bed packs {} grains, but the scene was counted with {} (a bed's count is the "
        "packing's: load the scene, or call resolve_beds, with this geometry and seed)",
        where, bed.size(), config_.count));
  bed_ = std::move(bed);
  if (bed_.size() == 0) return;
  slot_lo_ = slot_hi_ = bed_.x[0];
  for (std::size_t k = 0; k < bed_.size(); ++k) {
    slot_lo_ = min(slot_lo_, bed_.x[k]);
    slot_hi_ = max(slot_hi_, bed_.x[k]);
  }
}

std::uint64_t bed_seed(std::uint64_t scene_seed, std::size_t index) {
  // splitmix64 of the pair: beds of one scene, and scenes of neighbouring seeds, differ
  std::uint64_t z = scene_seed * 0x9e3779b97f4a7c15ULL + (index + 1) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

std::optional<EmitterProblem> pack_bed_emitter(const EmitterConfig& e, const MaterialConfig& m,
                                               const Geometry& geometry, std::uint64_t seed,
                                               BedPacking& out, Real max_grains, int threads) {
  if (auto problem = emitter_problem(e, m)) return problem;
  const Real d = m.largest_diameter();
  const Real top = e.height;
  // The floor: the highest solid top under (x, y) below the bed's top (a mesh by its crossings,
  // grown by its boundary particles), searched down to a metre (or 1000 grains) under the lowest
  // solid or the top. A point with none stops the bed.
  Vec3 lo, hi;
  Real bottom = top;
  if (geometry.finite_bounds(lo, hi)) bottom = std::min(bottom, lo.z);
  bottom -= std::max(1.0, 1000 * d);
  bool bottomless = false;
  Real bx = 0, by = 0;
  BedRegion region;
  region.x0 = e.center.x - e.size.x / 2;
  region.x1 = e.center.x + e.size.x / 2;
  region.y0 = e.center.y - e.size.y / 2;
  region.y1 = e.center.y + e.size.y / 2;
  // (looked for half a grain inside the footprint's edge: a container's wall, whose inner face is
  // the edge, is not the floor)
  const Real inset = 0.25 * m.smallest_diameter();
  region.floor = [&](Real x, Real y) {
    x = std::clamp(x, region.x0 + inset, region.x1 - inset);
    y = std::clamp(y, region.y0 + inset, region.y1 - inset);
    const auto solids = geometry.solid_intervals(x, y, top, bottom);
    if (solids.empty()) {
      if (!bottomless) bx = x, by = y;
      bottomless = true;
      return bottom;
    }
    return std::min(solids.back().second, top);
  };
  // the top: flat at `height`, or a smooth relief (the noise terrain of a heightmap, its own
  // seed) from height - relief up to height
  std::optional<SolidHeightmap> relief;
  if (e.relief > 0) {
    const std::array<Real, 4> extent{region.x0, region.y0, region.x1, region.y1};
    const Real wavelength = e.relief_wavelength.value_or(0.25 * std::min(e.size.x, e.size.y));
    relief.emplace(noise_heights(extent, wavelength, e.relief_seed, top - e.relief, top), extent,
                   e.relief);
    region.top = [&relief](Real x, Real y) { return relief->height(x, y); };
  } else {
    region.top = [top](Real, Real) { return top; };
  }
  // a grain reaching into a solid by more than 1 % of d is refused (the floor is sampled and
  // met through tangent planes: a grain may rest a hair into a curved one)
  const Real tolerance = 0.01 * d;
  region.blocked = [&](const Vec3& c, Real r) {
    for (const Obstacle& o : geometry.obstacles())
      if (o.solid->closest(c).distance < r - tolerance) return true;
    for (const MeshObstacle& mesh : geometry.meshes())
      if (mesh.winding->inside(c)) return true;
    return false;
  };
  region.r_lo = 0.5 * m.smallest_diameter();
  region.r_hi = 0.5 * m.largest_diameter();
  region.seed = seed;
  region.max_grains = max_grains;
  region.threads = threads > 0 ? threads : default_thread_count();
  try {
    // a coarse look first (33 x 33 points), so that a bed far too large is refused at once
    Real coarse = 0;
    for (int j = 0; j <= 32; ++j)
      for (int i = 0; i <= 32; ++i) {
        const Real x = region.x0 + (region.x1 - region.x0) * i / 32;
        const Real y = region.y0 + (region.y1 - region.y0) * j / 32;
        coarse += std::max(0.0, region.top(x, y) - region.floor(x, y)) / (33.0 * 33.0);
      }
    coarse *= (region.x1 - region.x0) * (region.y1 - region.y0) * 0.6 /
              (4.0 / 3.0 * kPi * std::pow(0.5 * m.diameter, 3));
    const Real estimate = coarse > 4 * max_grains ? coarse : estimate_bed_grains(region);
    if (bottomless)
      return EmitterProblem{
          "center", fmt::format("puts the bed over ({:.4g}, {:.4g}) m, where no solid lies under "
                                "its top (z = {:.4g} m): a bed rests on the scene's geometry",
                                bx, by, top)};
    if (estimate > max_grains)
      return EmitterProblem{
          "size", fmt::format("makes a bed of about {:.3g} grains, more than the limit of {:.0f}",
                              estimate, max_grains)};
    out = pack_bed(region);
  } catch (const std::length_error& err) {
    return EmitterProblem{"size", fmt::format("makes too large a bed ({})", err.what())};
  } catch (const std::invalid_argument& err) {
    return EmitterProblem{"size", fmt::format("cannot be packed ({})", err.what())};
  }
  if (out.size() == 0)
    return EmitterProblem{
        "height", fmt::format("= {:.4g} m leaves no room for a grain of {:.4g} m over the floor "
                              "under the footprint",
                              top, 2 * region.r_lo)};
  return std::nullopt;
}

void resolve_beds(SceneConfig& scene) {
  bool any = false;
  for (const EmitterConfig& e : scene.emitters) any = any || e.type == EmitterType::Bed;
  if (!any) return;
  const Geometry geometry = Geometry::from_config(scene.geometry, scene.material, scene.path);
  for (std::size_t k = 0; k < scene.emitters.size(); ++k) {
    EmitterConfig& e = scene.emitters[k];
    if (e.type != EmitterType::Bed) continue;
    BedPacking bed;
    if (const auto problem =
            pack_bed_emitter(e, scene.material, geometry, bed_seed(scene.simulation.seed, k), bed,
                             kMaxBedGrains, scene.simulation.threads))
      throw InputError(fmt::format("{}: emitter[{}].{} {}",
                                   scene.place({fmt::format("emitter[{}].{}", k, problem->key),
                                                fmt::format("emitter[{}]", k)}),
                                   k, problem->key, problem->what));
    set_bed_extent(e, bed);
  }
}

void set_bed_extent(EmitterConfig& e, const BedPacking& bed) {
  e.count = static_cast<std::int64_t>(bed.size());
  Real z_lo = bed.x[0].z - bed.r[0], z_hi = bed.x[0].z + bed.r[0];
  for (std::size_t k = 0; k < bed.size(); ++k) {
    z_lo = std::min(z_lo, bed.x[k].z - bed.r[k]);
    z_hi = std::max(z_hi, bed.x[k].z + bed.r[k]);
  }
  e.center.z = 0.5 * (z_lo + z_hi);
  e.size.z = z_hi - z_lo;
}

void Emitter::near_box(Real r, Vec3& lo, Vec3& hi) const {
  const Real m = reach_ + drop_ + r;
  lo = slot_lo_ - Vec3{m, m, m};
  hi = slot_hi_ + Vec3{m, m, m};
}

bool Emitter::near_slots(const Vec3& x, Real r) const {
  const Real m = reach_ + drop_ + r;
  return x.x > slot_lo_.x - m && x.x < slot_hi_.x + m && x.y > slot_lo_.y - m &&
         x.y < slot_hi_.y + m && x.z > slot_lo_.z - m && x.z < slot_hi_.z + m;
}

std::string Emitter::warning() const {
  if (config_.type != EmitterType::Pour || stream_lead_ >= 1) return "";
  if (config_.facing == PourFacing::Velocity) return "";  // (a stream without leads)
  if (!pour_falls(config_, gravity_))
    return fmt::format(
        "{}: thrown up, or under gravity not along z, this pour falls as discs (each batch a layer "
        "of grains){}",
        where_, norm(config_.velocity) > 0 ? kNozzleAdvice : "");
  // (the wider spacings are searched only here: a World built to read a run back never asks)
  return broken_stream_warning(config_, material_, gravity_, where_, stream_lead_, stream_checked_);
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

  // a place is taken when a grain already there would overlap a new grain at it: placing one
  // there would fire both off. A pour owes the grains of taken slots to its next batches; a block,
  // a lattice or a bed leaves them out. (reach_ >= d_max_ / 2 covers a bed's grains too.)
  const Occupancy old_grains(nearby_x, nearby_r, reach_);
  if (config_.type == EmitterType::Bed) {
    // the packed grains, at rest (the World seats them in surface mode)
    out.reserve(out.size() + bed_.size());
    for (std::size_t k = 0; k < bed_.size(); ++k) {
      if (old_grains.taken(bed_.x[k], bed_.r[k])) {
        ++left_out_;
        continue;
      }
      out.push_back({bed_.x[k], Vec3{}, bed_.r[k]});
      ++emitted_;
    }
    bed_ = {};
    return;
  }
  if (config_.type != EmitterType::Pour) {
    out.reserve(out.size() + static_cast<std::size_t>(config_.count));
    for_each_box_slot([&](const Vec3& p) {
      if (old_grains.taken(p, reach_)) {
        ++left_out_;
        return;
      }
      out.push_back({jittered(p), config_.velocity, draw_radius(rng)});
      ++emitted_;
    });
    return;
  }
  // pour: a batch of randomly chosen free slots, emitted tau after its time (it waited for a
  // rebuild of the pair list, or for the step), each grain placed and moving as free fall since
  // its time, and its slot's lead, would have it, so that the wait changes nothing while they fly
  const Real tau = std::max(0.0, t - next_time_);
  owed_ += per_batch_;
  auto k = static_cast<std::int64_t>(owed_);
  k = std::min<std::int64_t>(
      {k, config_.count - emitted_, static_cast<std::int64_t>(slots_.size())});
  owed_ -= static_cast<Real>(k);
  std::vector<std::uint32_t> order(slots_.size());
  for (std::uint32_t q = 0; q < order.size(); ++q) order[q] = q;
  std::int64_t placed = 0;
  for (std::size_t q = 0; q < order.size() && placed < k; ++q) {  // partial Fisher-Yates
    const auto pick =
        q + static_cast<std::size_t>(rng.uniform() * static_cast<Real>(order.size() - q));
    std::swap(order[q], order[std::min(pick, order.size() - 1)]);
    const Real fall = tau + slot_lead_[order[q]];
    const Vec3 slot = slots_[order[q]] + config_.velocity * fall + gravity_ * (fall * fall / 2);
    if (old_grains.taken(slot, reach_)) continue;  // (the top of a heap grown up to the pour)
    out.push_back({jittered(slot), config_.velocity + gravity_ * fall, draw_radius(rng)});
    ++placed;
  }
  owed_ += static_cast<Real>(k - placed);  // the grains of taken slots come with later batches
  delayed_ += k - placed;
  emitted_ += placed;
  next_time_ += batch_interval_;
}

}  // namespace sandflow

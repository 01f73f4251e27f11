// Emitters (docs/design.md §7): where grains come from. A pour drops batches from a disk or a
// rectangle, each batch placed on free slots of a hexagonal pattern so that no two new grains
// overlap, and the next batch waits until the last one has fallen one slot spacing; a slot's
// grains leave a fixed part of an interval early (less when thrown sideways, where their paths
// cross), so that the stream does not fall as discs. A block fills a box with a jittered cubic
// lattice and gives it a velocity (a splash, a wave); a lattice fills a box with a close-packed
// (FCC) lattice at rest (a prefilled pile). A bed fills a footprint, from the scene's geometry up
// to a height, with a random packing at rest (geometry/bed_packing.hpp), made once when the scene
// is loaded (resolve_beds: it decides the count) and again, the same, by the World.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "config/scene_config.hpp"
#include "core/rng.hpp"
#include "core/vec3.hpp"
#include "dem/grains.hpp"
#include "geometry/bed_packing.hpp"
#include "geometry/shapes.hpp"

namespace sandflow {

/// The most slots a pour's pattern (one layer over its disk or rectangle) may hold: 2^24, 400 MB
/// of slot centres. A larger one is refused before any slot is made.
inline constexpr Real kMaxPourSlots = 16'777'216;
/// Slots are placed by adding spacings to a corner: 2^40 spacings from the origin, a double still
/// tells neighbouring slots apart to a part in 4,000 of the spacing; farther, it soon does not.
inline constexpr Real kMaxSpacingsFromOrigin = 1'099'511'627'776.0;

/// What makes an emitter impossible whatever its count: a pour of more than kMaxPourSlots slots
/// (the scene's pours together: the loader),
/// a box too thin for one grain, or coordinates too far out for its spacing.
struct EmitterProblem {
  const char* key;   ///< the scene key at fault ("radius", "size", "center")
  std::string what;  ///< the rest of the message, after the key's name
};
std::optional<EmitterProblem> emitter_problem(const EmitterConfig& e, const MaterialConfig& m);

/// About how many slots a pour's one layer has (0 for a block or a lattice): counted, not made.
Real pour_slots(const EmitterConfig& e, const MaterialConfig& m);

/// How many grains a block's or lattice's box holds (0 for a pour): counted, not made, from the
/// same rows the emitter places.
Real box_slots(const EmitterConfig& e, const MaterialConfig& m);

/// The most grains a bed may hold: 2^31 - 1 (its grains are numbered by 32-bit ids; the scene's
/// limit, 2e9 in all, is below it and is checked by the loader).
inline constexpr Real kMaxBedGrains = 2147483647.0;

/// The seed of the bed emitter[index] of a scene seeded `scene_seed`: each bed its own packing.
std::uint64_t bed_seed(std::uint64_t scene_seed, std::size_t index);

/// Packs the bed `e` (EmitterType::Bed) on `geometry`: the footprint e.center.xy +- e.size.xy / 2,
/// the floor the highest solid top under each point below e.height, grains wholly outside every
/// solid (to 1 % of a diameter). Returns what makes it impossible (the key at fault and the rest of
/// the message: no solid under the footprint, no room for a grain, more than max_grains), or fills
/// `out`. It packs on `threads` threads (0: all cores), the same bed for any number.
std::optional<EmitterProblem> pack_bed_emitter(const EmitterConfig& e, const MaterialConfig& m,
                                               const Geometry& geometry, std::uint64_t seed,
                                               BedPacking& out, Real max_grains = kMaxBedGrains,
                                               int threads = 1);

/// Sets count, center.z and size.z of every bed of the scene from its packing (the loader does it
/// with the file's places; a scene built in code calls this). Throws InputError naming the bed.
void resolve_beds(SceneConfig& scene);
/// The count, center.z and size.z of the bed `e` from its packing (not empty).
void set_bed_extent(EmitterConfig& e, const BedPacking& bed);

struct NewGrain {
  Vec3 x, v;
  Real r;
};

class Emitter {
 public:
  /// Validates the emitter against the material and gravity (InputError naming `where`). Nothing
  /// of the size of `count` is made here: block and lattice grains are placed when emitted.
  Emitter(const EmitterConfig& config, const MaterialConfig& material, const Vec3& gravity,
          const std::string& where);

  /// Appends the grains due by time t (radii drawn from rng), none where it would overlap one of
  /// `nearby` (the grains already near its places, near_slots: centres and radii). A pour owes
  /// the grains of such slots to its next batches; a block, a lattice or a bed leaves them out
  /// (left_out()).
  void emit(Real t, Rng& rng, std::vector<NewGrain>& out, const std::vector<Vec3>& nearby_x = {},
            const std::vector<Real>& nearby_r = {});

  /// True when a batch is due at time t.
  bool due(Real t) const { return !done() && t >= next_time_; }
  /// How long a due batch of a pour may wait (to join the next rebuild of the pair list): half
  /// the time between batches, so that batches never merge. Its grains are placed where their
  /// free fall since the batch's time has brought them. 0 for a block or a lattice.
  Real max_wait() const { return config_.type == EmitterType::Pour ? batch_interval_ / 2 : 0; }
  /// A bed: its grains, packed (the World's, from the geometry); emitted at once at `start`, at
  /// rest. InputError when their number is not the count the scene was loaded with.
  void set_bed(BedPacking bed, const std::string& where);
  /// Pour: the most grains per second its slots let through without overlaps (0 otherwise).
  Real max_rate() const {
    return batch_interval_ > 0 ? static_cast<Real>(slots_.size()) / batch_interval_ : 0;
  }
  /// Time of the next batch [s].
  Real next_time() const { return next_time_; }
  /// True when a grain centred at x with radius r may overlap a new grain of this emitter.
  bool near_slots(const Vec3& x, Real r) const;
  /// The box [lo, hi] that holds the centre of every grain of radius up to r near_slots.
  void near_box(Real r, Vec3& lo, Vec3& hi) const;
  /// Grains a pour owed but could not place because its slots were occupied (summed per batch).
  std::int64_t delayed() const { return delayed_; }
  /// Grains of a block, lattice or bed not placed because grains already there took their places.
  std::int64_t left_out() const { return left_out_; }
  const std::string& name() const { return config_.name; }
  EmitterType type() const { return config_.type; }
  /// Pour: which way its area faces (up: level; velocity: a nozzle).
  PourFacing facing() const { return config_.facing; }

  /// How far the emitter has got: what a restart needs (the rest follows from the scene).
  struct Progress {
    Real owed = 0;        ///< pour: fractional grains carried to the next batch
    Real next_time = 0;   ///< time of the next batch [s]
    std::int64_t emitted = 0, delayed = 0, left_out = 0;
  };
  Progress progress() const { return {owed_, next_time_, emitted_, delayed_, left_out_}; }
  void restore(const Progress& p) {
    owed_ = p.owed;
    next_time_ = p.next_time;
    emitted_ = p.emitted;
    delayed_ = p.delayed;
    left_out_ = p.left_out;
    if (done()) bed_ = {};  // (a bed emitted before the checkpoint: its grains are in the state)
  }

  /// A pour's slots lead their batches by up to this share of a batch interval, each its own
  /// share of it: 1 for a stream straight down, less for one thrown sideways, 0 for discs and for
  /// a nozzle (its batches leave one behind the other along its throw: a stream without leads).
  Real stream_lead() const { return stream_lead_; }
  /// What a run says of this emitter at its start (empty: nothing): a pour that cannot fall as a
  /// whole stream, and the spacing that would let it (searched for at each call).
  std::string warning() const;
  /// Time the last grain is emitted [s].
  Real end_time() const;
  std::int64_t emitted() const { return emitted_; }
  std::int64_t count() const { return config_.count; }
  bool done() const { return emitted_ + left_out_ >= config_.count; }

 private:
  Real draw_radius(Rng& rng) const;
  /// Calls f(p) on the first `count` points of a block's or lattice's box, in emission order;
  /// returns how many there were (fewer than count when the box is too small).
  template <class F>
  std::int64_t for_each_box_slot(F&& f) const;

  EmitterConfig config_;
  MaterialConfig material_;
  Real d_max_;               ///< largest diameter [m]
  Real spacing_;             ///< slot spacing [m]
  std::vector<Vec3> slots_;  ///< pour: slot centres (one layer)
  std::vector<Real> slot_lead_;  ///< pour: how long each slot's grains have fallen at birth [s]
  Real stream_lead_ = 0;     ///< pour: the largest lead, in batch intervals (0: it falls as discs)
  bool stream_checked_ = true;  ///< pour: its slot pairs were few enough to check their paths
  std::string where_;           ///< where its table is in the scene file (for warning())
  Real batch_interval_ = 0;  ///< pour: time between batches [s]
  Real per_batch_ = 0;       ///< pour: grains per batch (fractional)
  Real owed_ = 0;            ///< pour: fractional grains carried to the next batch
  Real next_time_ = 0;       ///< time of the next batch [s]
  Vec3 gravity_;             ///< [m/s^2]
  Real reach_ = 0;           ///< largest distance of a new grain's surface from its slot [m]
  Real drop_ = 0;            ///< pour: more than a batch can fall during its wait [m]
  Vec3 slot_lo_, slot_hi_;   ///< bounds of the slot centres (pour) or of the grains (box, bed) [m]
  std::int64_t emitted_ = 0;
  std::int64_t delayed_ = 0;
  std::int64_t left_out_ = 0;
  BedPacking bed_;  ///< bed: its grains until they are emitted
};

}  // namespace sandflow

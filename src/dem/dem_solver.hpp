// One DEM step over the hot grains (docs/design.md §3): neighbours, contact forces, integration.
// Both modes of sandflow call exactly this code; surface mode only changes which grains are hot.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "core/timer.hpp"
#include "dem/contact.hpp"
#include "dem/grains.hpp"
#include "dem/neighbor_list.hpp"
#include "geometry/shapes.hpp"

namespace sandflow {

struct DemParams {
  ContactParams contact;  ///< grain-grain law (walls use it with their own friction)
  /// Some wall or mesh resists rolling or twisting (its own mu_r or mu_tw), whatever the grains do.
  bool walls_resist_turning = false;
  Real skin = 0.002;      ///< Verlet skin [m]: each grain may move skin / 2 between rebuilds
  /// A grain faster than skin / (2 dt skin_steps) may move |v| dt skin_steps, up to skin_max, so
  /// that a few fast grains do not force a rebuild every few steps (0: skin / 2 for all).
  int skin_steps = 0;
  Real skin_max = 0;      ///< largest allowance of a fast grain [m]
  int sort_every = 20;    ///< re-sort grains by cell every N rebuilds (0: never)
  /// A preloaded contact's rest overlap decays with this time constant, so that two grains a
  /// change of state left inside each other are pushed apart slowly: the dashpot takes up the
  /// motion, and the spring does only the work of moving them (0: it never decays) [s]
  Real preload_relax_time = 0;
  Vec3 gravity{0, 0, -9.81};
};

/// Fixed spheres that stand for a mesh's surface (its "particle surface", docs/design.md §6): ACTIVE
/// grains collide with them by the grain-grain law, as with a grain that never moves.
struct BoundaryParticles {
  std::vector<Vec3> x;                 ///< centres [m]
  std::vector<std::uint32_t> group;    ///< the mesh each belongs to
  Real radius = 0;                     ///< [m]
  std::vector<Real> friction, rolling_friction, twisting_friction;  ///< per group [-]
  std::size_t size() const { return x.size(); }
};

/// What the last steps saw; reset by the caller when it reads them.
struct DemCounters {
  std::int64_t contacts = 0;     ///< touching grain-grain pairs, at the last step
  std::int64_t wall_contacts = 0;
  Real max_overlap_rel = 0;      ///< largest overlap / smaller diameter, since the last reset
  std::int64_t rebuilds = 0;     ///< neighbour-list rebuilds, since the last reset
  std::int64_t near_builds = 0;  ///< near lists made (at each rebuild and between), since then
  // Energy through the changes of state (surface mode), since the last reset [J]:
  Real energy_inert = 0;      ///< in the springs of contacts that went inert as both grains froze
  Real energy_released = 0;   ///< added: energy_inside, and the work of the springs of
                              ///< preloaded contacts as their rest overlap decays
  Real energy_inside = 0;     ///< in the springs of contacts a released grain opened inside an
                              ///< ACTIVE one, deeper than one step: the invariant says none
  Real energy_preloaded = 0;  ///< withheld: contacts opened inside between grains frozen before
};

/// What a restart needs of a DemSolver between two steps (src/checkpoint/): the lists in their
/// order with their contact history, where each grain stood at the last rebuild and how far it may
/// move, and the counters that decide the next rebuild and sort. The rest is scratch, or follows
/// from the scene.
struct DemState {
  PairList pairs;  ///< start, j, touch, c_n, xi, psi (force, q, t_roll are per-step scratch)
  WallList walls;
  WallList bounds;                          ///< boundary particles within reach
  std::vector<std::uint32_t> slot_of_id;    ///< grain id -> slot at the last rebuild
  std::vector<Vec3> x_at_build;             ///< [m]
  std::vector<Real> allow;                  ///< [m]
  bool need_rebuild = true;
  std::int64_t rebuild_count = 0;
};

/// A grain's change of state, as the surface flow decides it (src/surface/); DemSolver::apply
/// brings the lists and the contact history into line with a list of them.
struct StateChange {
  GrainId id;
  GrainState from, to;
};

/// The deepest overlap among the listed contacts (DemSolver::deepest_overlap).
struct DeepestOverlap {
  enum Kind { kNone, kGrain, kWall, kBoundary };
  Kind kind = kNone;
  Real rel = 0;              ///< overlap / smaller diameter (a wall: / the grain's diameter)
  std::uint32_t slot = 0;    ///< the grain's slot
  std::uint32_t other = 0;   ///< the other grain's slot, the obstacle or the boundary particle
};

/// The order DemSolver keeps its grains in: row-major over cells of side 2 r_max + skin, the
/// axis the grains spread furthest along outermost (dem_solver.cpp). Slot k of the sorted grains
/// holds perm[k].
std::vector<std::uint32_t> cell_order(const Grains& grains, Real skin);

/// The squared radius of the ball around x (where the grain stands as the near list is made) in
/// which it is inside its near margin, its allowance (around x_at_build) and the domain [lo, hi]:
/// the sweep tests this ball alone and the three only outside it (DemSolver::watch2_), -1 when
/// the grain is outside one already. A billionth of slack, and a few ulps of the coordinates,
/// keep the triangle inequality true through the tests' rounding (of order 1e-16).
Real watch_radius2(const Vec3& x, Real margin, Real allow, const Vec3& x_at_build, const Vec3& lo,
                   const Vec3& hi);

struct SweepTally;  // (one thread's tallies of a sweep: dem_solver.cpp)

class DemSolver {
 public:
  explicit DemSolver(const DemParams& params);

  /// Advances the ACTIVE grains by dt; INTERFACE grains push but stay put: update_lists, then
  /// advance, each timed as its stage of `profile` (World::step calls the two itself).
  void step(Grains& grains, const Geometry& geometry, Real dt, Profile& profile);
  /// Stage "neighbours": rebuilds the pair, wall and boundary lists for steps of dt when they are
  /// stale (a grain left its allowance, the grains or the geometry changed).
  void update_lists(Grains& grains, const Geometry& geometry, Real dt);
  /// Stage "forces": the contact forces and the integration, in one sweep over the grains (each
  /// grain moves as soon as its forces are summed, while its data are in cache); after
  /// update_lists.
  void advance(Grains& grains, const Geometry& geometry, Real dt);

  /// Sets the box the ACTIVE grains must stay in [m]: each sweep notes whether one left it, so
  /// that the caller's per-step guard need not read every grain again (all_inside).
  void set_domain(const Vec3& lo, const Vec3& hi) {
    domain_lo_ = lo;
    domain_hi_ = hi;
    maybe_outside_ = true;
    need_near_ = true;  // (the near list's build measures each grain's way to the domain's walls)
  }
  /// True when the last sweep left every ACTIVE grain inside the domain with a finite position
  /// (a non-finite velocity makes the position non-finite); false before the first sweep and after
  /// a restore, when it has not looked.
  bool all_inside() const { return !maybe_outside_; }

  /// Sets the boundary particles (before the first step).
  void set_boundary(BoundaryParticles boundary);
  const BoundaryParticles& boundary() const { return boundary_; }

  /// Call after grains were added, removed or changed state: the next step rebuilds the lists.
  void invalidate() { need_rebuild_ = true; }
  /// How far each grain may move before the lists are rebuilt, as a rebuild now would set it,
  /// into `out` (one per grain) [m]: half the skin, or for a fast ACTIVE grain the way it goes in
  /// skin_steps steps at the speed it may have, up to skin_max; a frozen grain none (it moves only
  /// through a change of state, which rebuilds). The speed a grain may have is its own, or that of
  /// a faster ACTIVE partner in the present lists close enough to meet it within skin_steps
  /// steps: a grain struck by a faster one leaves at up to the striker's speed, and with the
  /// allowance of its own old speed it would leave it within a few steps and force a rebuild.
  void allowances(const Grains& grains, Real dt, std::vector<Real>& out) const;
  /// The same, kept for the rebuild that follows before the next step: the invariant of the
  /// layers reads them just before it (SurfaceFlow::wake_within_reach), and computing them twice
  /// cost a surface run about 1 % of its time. What may come between leaves every other grain's
  /// allowance as it was: grains appended frozen (woken into the interface), which have no speed
  /// and, frozen, are raised by none. Anything else (a step, a sort, another change of state,
  /// grains removed) makes the rebuild compute them again.
  const std::vector<Real>& allowances_for_rebuild(const Grains& grains, Real dt);
  /// Applies the changes of state the surface flow decided, before the next step: a grain that
  /// goes to sleep leaves the lists, a woken one joins them without contact history, and a woken
  /// or dislodged one is released: the lists are rebuilt, and a contact it opens there with a
  /// grain that was frozen too starts at its present overlap (two frozen grains may lie inside
  /// each other, and the change must not turn that into energy). One it opens inside an ACTIVE
  /// grain deeper than the two close in one step (how deep any contact of the DEM may begin) is
  /// counted in DemCounters::energy_inside: the invariant of the layers says there is none. A
  /// trapped grain keeps the lists: its pairs with other frozen grains go inert in the sweep.
  void apply(std::span<const StateChange> changes);
  bool needs_rebuild() const { return need_rebuild_; }
  /// Drops the contact history of a grain (its pairs and wall contacts start afresh at the next
  /// rebuild, which this requests): for grains removed from the run, and woken ones (apply).
  void forget_history(GrainId id) {
    if (id < slot_of_id_.size()) slot_of_id_[id] = kNoSlot;
    need_rebuild_ = true;
  }

  /// Per grain, what it touched at the last step: kTouches (a grain or the geometry),
  /// kTouchesActive (an ACTIVE grain), kNearActive (an ACTIVE grain within the Verlet skin),
  /// kSeated (at least kSeatContacts grains, or the geometry: what holds a sphere at rest under
  /// gravity), kSlips (one of its grain contacts slipped: its tangential force at mu F_n).
  /// Grains added since the last rebuild get 0.
  static constexpr std::uint8_t kTouches = 1, kTouchesActive = 2, kNearActive = 4, kSeated = 8,
                                kSlips = 16;
  static constexpr int kSeatContacts = 3;
  void contacts_of(const Grains& grains, const Geometry& geometry,
                   std::vector<std::uint8_t>& out) const;

  /// The deepest overlap at the current positions over the listed pairs, walls and boundary
  /// particles: what a guard names when the overlap limit is passed.
  DeepestOverlap deepest_overlap(const Grains& grains, const Geometry& geometry) const;

  /// For restarts: the state above, and its restoration (validated by the caller).
  DemState save_state() const;
  void restore_state(DemState s, const Geometry& geometry);

  const DemParams& params() const { return params_; }
  /// The grains or the walls resist rolling or twisting: the law's rolling part runs, with the
  /// rolling history (psi), for every contact.
  bool resists_turning() const { return rolling_; }
  void set_gravity(const Vec3& g) { params_.gravity = g; }
  const PairList& pairs() const { return pairs_; }
  DemCounters& counters() { return counters_; }

  /// Whether this processor has AVX-512 (the sweep then runs its build for it, which gives the
  /// same results bit for bit, faster).
  static bool avx512_available();
  /// Runs the sweep's AVX-512 build (when available) or the portable one: for tests, which check
  /// that the two agree. Each solver starts with the AVX-512 build where there is one.
  void use_avx512(bool on) { use_avx512_ = on && avx512_available(); }

 private:
  /// A grain woken or dislodged (apply): consumed by the next rebuild, in the same step.
  void release(GrainId id) {
    released_.push_back(id);
    need_rebuild_ = true;
  }
  void rebuild(Grains& grains, const Geometry& geometry, Real dt);
  /// The near list: the listed pairs that may touch before some grain moves further than its
  /// near margin, with the contacts of those left out ended as the sweep would end them now.
  void build_near(const Grains& grains, Real dt);
  /// At a rebuild for steps of dt: the contacts of the released grains that open inside another
  /// grain.
  void open_released_contacts(const Grains& grains, Real dt);
  void set_wall_params(const Geometry& geometry);
  void sort_by_cell(Grains& grains);
  /// Forces and integration in one sweep (its kernels: dem_solver.cpp); returns whether some
  /// grain has moved further than its allowance since the last rebuild, or than its near margin
  /// since the near list was made (flags: dem_solver.cpp).
  template <bool kRolling>
  int sweep(Grains& grains, const Geometry& geometry, Real dt);
  /// One thread's part of the sweep, in its parallel region: its tallies into `tally`, and what
  /// its grains left (as sweep); compiled for x86-64 and, as sweep_part_avx512, for AVX-512.
  template <bool kRolling>
  int sweep_part(Grains& grains, const Geometry& geometry, Real dt, SweepTally& tally);
  template <bool kRolling>
  [[gnu::target("avx512f")]] int sweep_part_avx512(Grains& grains, const Geometry& geometry,
                                                   Real dt, SweepTally& tally);
  /// Splits the grains into `threads` contiguous ranges of about equal time for the sweep: each
  /// thread's share of the estimated work follows the speed it showed since the last split.
  void balance_ranges(const Grains& grains, std::size_t threads);

  DemParams params_;
  bool rolling_;  ///< resists_turning()
  bool use_avx512_;  ///< the sweep runs sweep_part_avx512
  std::vector<ContactParams> wall_params_;
  /// per obstacle: the plane it is, or null; found before each sweep (an obstacle can be
  /// replaced), so that the sweep calls a plane's closest point inline
  std::vector<const HalfSpace*> wall_planes_;
  PairGrids grids_;
  PairList pairs_, old_pairs_;
  WallList walls_, old_walls_;
  BoundaryParticles boundary_;
  std::vector<ContactParams> boundary_params_;  ///< per group
  CellGrid boundary_grid_;
  WallList bounds_, old_bounds_;  ///< per grain: the boundary particles it may touch
  std::vector<std::uint32_t> slot_of_id_;  ///< grain id -> slot at the last rebuild
  std::vector<GrainId> ids_at_build_;      ///< the ids slot_of_id_ holds a slot for
  std::vector<Vec3> x_at_build_;
  std::vector<Real> allow_, allow2_;  ///< per grain: how far it may move before a rebuild [m, m^2]
  /// allowances_for_rebuild's: the allowances and the ids of the grains they are for (empty when
  /// none are kept)
  std::vector<Real> kept_allow_;
  std::vector<GrainId> kept_ids_;
  /// The kept allowances are for these grains: the same ids first, then only frozen ones.
  bool kept_allowances_hold(const Grains& grains) const;
  std::vector<Vec3> acc_f_, acc_q_, acc_t_;  ///< per grain: reversed pair results of this step
  std::vector<Vec3> x_at_near_;  ///< per grain: where it stood when the near list was made
  std::vector<Real> near2_;      ///< per grain: its near margin, squared [m^2]
  /// per grain: the squared radius around x_at_near_ within which it is inside its near margin,
  /// its allowance and the domain (made with the near list; -1: outside one) [m^2]
  std::vector<Real> watch2_;
  bool need_near_ = true;
  static constexpr Real kFar = std::numeric_limits<Real>::infinity();
  Vec3 domain_lo_{-kFar, -kFar, -kFar}, domain_hi_{kFar, kFar, kFar};  ///< (set_domain)
  bool maybe_outside_ = true;                                          ///< (all_inside)
  /// The sweep's ranges, one per thread, of about equal work (set after each rebuild).
  std::vector<std::size_t> range_start_;
  std::vector<std::uint32_t> cross_rows_;  ///< ascending: rows with pairs past their range's end
  bool ranges_stale_ = true;
  std::vector<double> share_;  ///< per thread: its share of the estimated work
  std::vector<double> busy_;   ///< per thread: seconds in its range since the last split
  bool need_rebuild_ = true;
  std::int64_t rebuild_count_ = 0;
  std::vector<GrainId> released_;  ///< since the last rebuild (always empty between steps)
  DemCounters counters_;
};

}  // namespace sandflow

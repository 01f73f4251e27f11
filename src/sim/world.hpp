// A World is a scene brought to life: grains, geometry, emitters and the solver, stepped in the
// order of docs/design.md §1. The app drives it frame by frame and writes what it reports.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "config/scene_config.hpp"
#include "core/rng.hpp"
#include "core/timer.hpp"
#include "dem/dem_solver.hpp"
#include "dem/frame.hpp"
#include "dem/grains.hpp"
#include "geometry/shapes.hpp"
#include "sim/emitters.hpp"
#include "sim/stiffness.hpp"
#include "surface/surface_flow.hpp"

namespace sandflow {

/// The time step of a scene and the bound it must respect.
/// The most steps a frame may take: 10^8 (10 s a frame for a single grain, at best).
inline constexpr Real kMaxSubsteps = 100'000'000;
/// The most frames a run may plan: 10^7 (over 90 hours at 30 fps). With kMaxSubsteps a frame,
/// the step count stays far inside 64 bits and the frame count inside an int.
inline constexpr Real kMaxFrames = 10'000'000;

struct TimeStep {
  Real t_c;           ///< contact duration of the two smallest grains [s]
  Real stable_bound;  ///< largest dt accepted: t_c / 5, less for a strong dashpot [s]
  Real dt;            ///< the step used: frame time / substeps [s]
  int substeps;       ///< steps per frame
};

/// Derives dt from the scene (t_c * dt_fraction unless simulation.dt is set); throws InputError
/// with the bound when the scene's dt is above the stable bound, or when a frame would take more
/// than kMaxSubsteps steps.
TimeStep choose_time_step(const SceneConfig& scene);

/// Contact parameters of the grain-grain law from the material.
ContactParams contact_params(const MaterialConfig& m);

/// Scales every emitter's count so the scene makes `total` grains in all (largest remainder),
/// keeping the scene's character: a pour keeps its start and duration (its rate scales with its
/// count), so that a smaller run is a preview of the same shot; a block or lattice keeps its
/// proportions, the centre of its bottom face and its spacing (its box scales with the cube root
/// of its count, grown until the count fits). A bed keeps its region and its grains: the other
/// emitters make the rest (InputError when `total` leaves them none, or differs from the beds'
/// grains in a scene of beds only).
void scale_grain_count(SceneConfig& scene, std::int64_t total);

struct FrameStats {
  int frame = 0;
  Real time = 0;  ///< simulated time at the end of the frame [s]
  int substeps = 0;
  Real dt = 0;  ///< [s]
  std::int64_t n_total = 0, n_active = 0, n_interface = 0, n_static = 0;
  std::int64_t contacts = 0;  ///< touching grain-grain pairs at the end of the frame
  std::int64_t wall_contacts = 0;
  Real max_overlap_rel = 0;          ///< largest overlap / smaller diameter during the frame
  Real kinetic_energy = 0;           ///< translational + rotational [J]
  std::int64_t rebuilds = 0;         ///< neighbour-list rebuilds during the frame
  TransitionCounts transitions;      ///< grains that changed state during the frame
  /// Energy through the changes of state during the frame [J]: removed by trapping (the trapped
  /// grains' kinetic energy, and the springs of their contacts with frozen grains, which go
  /// inert), added by waking and dislodging (springs opened inside an ACTIVE grain: none while
  /// the invariant of the layers holds), and withheld by preloading the contacts a change of
  /// state opened between grains that were frozen inside each other (DemSolver::apply).
  Real energy_trapped = 0, energy_woken = 0, energy_preloaded = 0;
  /// Of energy_woken: the springs of contacts a woken or dislodged grain opened inside an ACTIVE
  /// grain, deeper than one step of motion (the invariant of the layers says none) [J].
  Real energy_inside = 0;
  std::int64_t surface_updates = 0;  ///< height-field updates during the frame
  std::int64_t left_domain = 0;      ///< grains removed on leaving the domain (on_leave = count)
  double wall_seconds = 0;           ///< wall-clock time of the frame [s]
};

/// The simulated fraction of frames [first, end): simulated grain-frames (ACTIVE + INTERFACE) over
/// all grain-frames, the share of plain DEM's grain work that a surface run does. (A mean of each
/// frame's fraction would weigh a pour's early frames, when few grains are in, as much as its
/// last ones.) Frames without grains: 1, nothing is saved.
double simulated_fraction(std::span<const FrameStats> frames, std::size_t first = 0);

/// Everything a restart needs to continue a World exactly as if it had not stopped
/// (src/checkpoint/ writes and checks it): the grains in their storage order, the solver's lists
/// and history, the height field, the emitters' progress, the random state and the counters.
struct WorldState {
  Grains grains;
  StaticStore::State statics;  ///< the static store's compact form, slot for slot
  DemState dem;
  std::optional<SurfaceState> surface;  ///< surface mode only
  std::vector<Emitter::Progress> emitters;
  std::array<std::uint64_t, 4> rng{};
  GrainId next_id = 0;
  std::int64_t step = 0;
  int frame = 0;
  std::int64_t left = 0;  ///< grains removed on leaving the domain
  Profile profile;        ///< seconds per stage so far (timings only)
};

class World {
 public:
  explicit World(const SceneConfig& scene);

  /// Advances one frame (TimeStep::substeps steps) and returns its statistics.
  FrameStats advance_frame();

  /// Gravity from the next step on, for a plain-DEM test that tilts it instead of the geometry
  /// (calibration). Not kept by checkpoints; std::logic_error in surface mode, whose height field
  /// stands along z.
  void set_gravity(const Vec3& g);

  /// Number of frames the scene asks for (output.frames, output.duration, or emission + settle);
  /// throws InputError, naming the keys, when that is more than kMaxFrames.
  int planned_frames() const;

  const SceneConfig& scene() const { return scene_; }
  const TimeStep& time_step() const { return ts_; }
  const Grains& grains() const { return grains_; }
  const StaticStore& static_grains() const { return static_; }
  const Geometry& geometry() const { return geometry_; }
  const Stiffness& stiffness() const { return stiffness_; }
  /// The height field and interface; nullptr in DEM mode.
  const SurfaceFlow* surface() const { return surface_.get(); }
  const DemSolver& dem() const { return dem_; }
  const Profile& profile() const { return profile_; }
  const std::vector<Emitter>& emitters() const { return emitters_; }
  /// What a run says of its world at the start: the geometry's warnings, then the emitters'.
  std::vector<std::string> warnings() const;
  Real time() const { return time_; }
  int frame() const { return frame_; }
  std::int64_t total_grains() const {
    return static_cast<std::int64_t>(grains_.size() + static_.size());
  }

  /// Centres and radii of every grain, hot and static.
  void all_grains(std::vector<Vec3>& x, std::vector<Real>& r) const;
  /// Every grain, hot and static (state 2, zero velocity), of the current state.
  FrameData all_grains_frame() const;
  /// The visible grains (ACTIVE and INTERFACE) of the current state.
  FrameData visible_frame() const;
  /// Hash of every grain's id, position, velocity and spin, in id order.
  std::uint64_t state_hash() const;
  Real kinetic_energy() const;

  /// The box the ACTIVE grains must stay in [m] (simulation.domain, or derived from the scene).
  const Vec3& domain_lo() const { return domain_lo_; }
  const Vec3& domain_hi() const { return domain_hi_; }
  /// Grains removed so far on leaving the domain (simulation.on_leave = "count").
  std::int64_t left_domain() const { return left_; }
  std::int64_t step_count() const { return step_; }

  /// For restarts, at a frame boundary: the state, and its restoration (checked by the caller,
  /// src/checkpoint/, against this scene).
  WorldState save_state() const;
  void restore_state(WorldState s);

 private:
  /// One step of dt, stage by stage (docs/design.md §1).
  void step();
  // The stages of a step that are the World's own (neighbours and forces are DemSolver's).
  /// Guards: the solids whose time has come are removed, then check_grains.
  void begin_step();
  void emit();
  /// Throws InputError when a grain emitter k placed this step (new_grains_ from `first` on) lies
  /// deeper in a solid than simulation.max_overlap_stop.
  void check_emitted(std::size_t k, std::size_t first) const;
  /// A bed's grains, in surface mode: to the layers where they rest (SurfaceFlow::seat_bed).
  void seat_bed(Emitter& e);
  /// Height field: measure H, evolve h through the exchange (an update, every update_steps).
  void update_height_field();
  /// Impacts: the static top held below the grains that move the pile (the same update).
  void apply_impacts();
  /// Transfer: trap, dislodge, sleep and wake after an update, or what the last update left
  /// waiting for a rebuild of the pair list; the DEM applies the changes.
  void transfer(bool after_update);
  /// Reach: the invariant of the layers, before a rebuild of the pair list.
  void hold_invariant();
  /// Counts the transitions of a stage, and has the DEM apply its changes of state.
  void apply(const Transitions& t);
  /// Guards after the DEM: check_overlap, and (assertions) the stores and the frozen grains.
  void end_step();
  /// Guards (docs/scenes.md): a non-finite grain stops the run; a grain outside the domain stops
  /// it or, with on_leave = "count", is marked for removal (leaving_).
  void check_grains();
  /// Removes the grains marked by check_grains (after the surface update: its contact flags
  /// need the lists of the last rebuild, whose slots a removal would shift).
  void remove_leaving();
  /// Guard: an overlap above simulation.max_overlap_stop stops the run.
  void check_overlap(std::int64_t after_step);
  /// Removes the geometry entries whose remove_at has come by step `before` (those due at a step
  /// index < before): each at the first step that starts at or after its time. `announce`: the
  /// pair lists are rebuilt at once (a restore finds them rebuilt by the checkpoint's state).
  void remove_due_geometry(std::int64_t before, bool announce);
  /// "step S (frame F, t = T s)" for the messages of the guards.
  std::string where(std::int64_t step) const;

  Geometry geometry_;
  Stiffness stiffness_;
  SceneConfig scene_;  ///< as given, with k_n from the stiffness choice
  TimeStep ts_;
  Grains grains_;
  StaticStore static_;
  DemSolver dem_;
  std::unique_ptr<SurfaceFlow> surface_;
  TransitionCounts transitions_;  ///< since the start of the frame
  std::int64_t surface_updates_ = 0;
  std::vector<Emitter> emitters_;
  Rng rng_;
  std::vector<NewGrain> new_grains_;
  std::vector<Vec3> nearby_x_;  ///< grains near an emitter's places
  std::vector<Real> nearby_r_;
  GrainId next_id_ = 0;
  Real time_ = 0;
  std::int64_t step_ = 0;
  int frame_ = 0;
  Profile profile_;
  Vec3 domain_lo_, domain_hi_;
  std::vector<GrainId> leaving_;  ///< marked this step, removed before the DEM step
  /// Per [[geometry]] entry, the step whose start removes it (-1: never, or done)
  std::vector<std::int64_t> removal_step_;
  std::int64_t left_ = 0, left_frame_ = 0;
  /// (assertions) the stores as store_error last found them sound: it depends on nothing else, so
  /// a step that changed neither (most steps) is not checked again
  struct CheckedStores {
    std::uint64_t static_revision = 0;
    std::vector<GrainId> ids;
    std::vector<GrainState> states;
    GrainId next_id = 0;
    std::int64_t expected = -1;
  } checked_;
};

}  // namespace sandflow

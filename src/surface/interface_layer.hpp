// The particle interface (docs/design.md §5): the band of frozen grains, of constant thickness T
// just below the static top h, through which matter passes between the grains and the height field.
// After each height-field update every grain is classified against h at its own (x, y), with the
// band measured normal to the local slope (T / cos theta in the vertical); "held" is seat.hpp's
// rule (seated, no contact slipping, too slow to leave its seat):
//
//   ACTIVE    centre below h and held   -> INTERFACE (trapped: v = w = 0; its contacts with
//                                                     other frozen grains go inert)
//   INTERFACE centre above h            -> ACTIVE    (dislodged, from rest)
//   INTERFACE centre below h - T        -> STATIC    (sleeps: leaves the DEM, filed by column;
//                                                     anywhere below h in a closed column)
//   STATIC    centre above h - T        -> INTERFACE (wakes: only where h fell; ACTIVE if above
//                                                     h + m, where a blow opened the bed)
//
// The invariant that makes the layers safe: no STATIC grain lies within reach of an ACTIVE grain,
// reach being what the two can close before the pair list is rebuilt again. STATIC grains push
// nothing, so a grain that reached one would go into it. wake_within_reach() enforces it exactly
// before every rebuild, for the allowances that rebuild gives; between rebuilds no grain moves
// further than its allowance, so no ACTIVE grain ever touches a STATIC one.
//
// A column is closed when no grain has moved the pile there for a while (HeightField::closed):
// its top is then static like the rest, and a bed at rest costs nothing; what comes near wakes.
//
// The band has a margin m of hysteresis: trapped below h, dislodged only above h + m; sleeps
// below h - T - m, wakes above h - T. H is measured from grains, so h jitters by a fraction of a
// grain; without the margin the same grains would flip state at every update.
//
// Grains below their column's level (under an overhang whose top holds the column's sand, or
// beside a wall whose top the column centre sits on) are outside the height field's reach: they
// stay ACTIVE, and static ones wake when a column's level rises above them.
#pragma once

#include <cstdint>
#include <vector>

#include "dem/dem_solver.hpp"
#include "dem/grains.hpp"
#include "surface/column_set.hpp"
#include "surface/height_field.hpp"
#include "surface/seat.hpp"
#include "surface/static_reach.hpp"

namespace sandflow {

struct TransitionCounts {
  std::int64_t trapped = 0, dislodged = 0, slept = 0, woken = 0;
  std::int64_t woken_by_reach = 0;  ///< static grains an ACTIVE grain came within reach of
  Real energy_trapped = 0;          ///< kinetic energy the trapped grains had [J]
  TransitionCounts& operator+=(const TransitionCounts& o) {
    trapped += o.trapped;
    dislodged += o.dislodged;
    slept += o.slept;
    woken += o.woken;
    woken_by_reach += o.woken_by_reach;
    energy_trapped += o.energy_trapped;
    return *this;
  }
  std::int64_t total() const { return trapped + dislodged + slept + woken + woken_by_reach; }
};

/// What a transfer decided: grain by grain, the changes of state, which the DEM applies before
/// its next step (DemSolver::apply: the surface flow does not touch the solver), and their counts
/// for the statistics.
struct Transitions {
  std::vector<StateChange> changes;
  TransitionCounts counts;
};

struct InterfaceParams {
  Real thickness = 0.015;   ///< T [m]
  SeatParams seat;          ///< which grains are held
  Real margin = 0.0025;     ///< hysteresis of the band's edges [m]
  Real density = 2600;      ///< to restore the mass of a woken grain [kg/m^3]
  /// The blow rule (surface.blows): bodies striking the bed open it as far as their momentum
  /// reaches, and a grain woken above h there moves at once (SurfaceFlow::apply_impacts).
  bool blows = false;
  Real friction = 0.6;  ///< the grains' friction: how soon a blow's moving bed stops
};

/// The thickness in the vertical of a band `thickness` thick normal to a slope `theta` [rad]: T /
/// cos theta, with theta at most 60 degrees (a column beside a wall sees the wall as its slope).
Real vertical_band(Real thickness, Real theta);

/// The frame of the static store filed by `hf`'s columns: static centres in [z_lo, z_hi] and
/// radii in [r_lo, r_hi] [m].
StaticFrame static_frame(const HeightField& hf, Real z_lo, Real z_hi, Real r_lo, Real r_hi);

class InterfaceLayer {
 public:
  explicit InterfaceLayer(const InterfaceParams& p) : p_(p) {}

  /// Per column, the highest point a STATIC grain reaches under its thick ray (or L). transfer()
  /// keeps it up to date as grains sleep and wake; it is computed from all static grains only
  /// at the first call, after a restart and where a column's level changed.
  const std::vector<Real>& static_tops(const HeightField& hf, const StaticStore& st);
  /// The columns whose static top changed since the last call (HeightField::measure's
  /// changed_tops); null when any may have (the tops were computed afresh).
  const std::vector<std::uint32_t>* take_changed_tops();

  /// Makes the four transitions against the current h, in the stores; returns them, for the DEM
  /// to apply. `contacts` is DemSolver::contacts_of for the hot grains. Without `list_changes`
  /// only trapping happens (it keeps the pair list); the rest waits for a later call with them,
  /// which wakes grains wherever h fell since the last such call. `moved` lists the columns
  /// whose h or L changed since then (HeightField::take_moved; null: any may have).
  Transitions transfer(const HeightField& hf, Grains& hot, StaticStore& st,
                       const std::vector<std::uint8_t>& contacts, bool list_changes = true,
                       const std::vector<std::uint32_t>* moved = nullptr);

  /// The invariant: wakes (to INTERFACE) every STATIC grain k within reach of an ACTIVE grain i,
  /// |x_i - x_k| < r_i + r_k + allow[i], allow[i] being how far the coming rebuild lets i move
  /// (DemSolver::allowances). Call it before every rebuild of the pair list, after the transfer;
  /// returns the woken grains, for the DEM to apply.
  Transitions wake_within_reach(const HeightField& hf, Grains& hot, StaticStore& st,
                                const std::vector<Real>& allow);

  const InterfaceParams& params() const { return p_; }
  /// For restarts: h and L as the last transfer saw them (empty before the first).
  const std::vector<Real>& h_seen() const { return h_seen_; }
  const std::vector<Real>& L_seen() const { return L_seen_; }
  void restore_seen(std::vector<Real> h_seen, std::vector<Real> L_seen) {
    h_seen_ = std::move(h_seen);
    L_seen_ = std::move(L_seen);
    tops_of_ = kNoTops;
    reach_ = {};
  }

 private:
  InterfaceParams p_;
  std::vector<Real> h_seen_;  ///< h at the last transfer: where it fell, static grains may wake
  std::vector<Real> L_seen_;  ///< L at the last transfer: where it rose, grains below it wake

  /// static_tops() of the store when it held tops_of_ grains, over the levels tops_L_.
  static constexpr std::size_t kNoTops = static_cast<std::size_t>(-1);
  std::vector<Real> tops_, tops_L_;
  std::size_t tops_of_ = kNoTops;
  std::uint64_t tops_level_ = 0;  ///< HeightField::level_revision() of tops_L_
  Real tops_r_max_ = 0;  ///< the largest static grain's radius
  ColumnSet tops_changed_;  ///< columns whose top changed since take_changed_tops()
  bool tops_all_changed_ = true;
  std::vector<std::uint32_t> tops_changed_out_;
  /// Column c's top is now `top`.
  void set_top(std::size_t c, Real top) {
    if (top == tops_[c]) return;
    tops_[c] = top;
    if (!tops_all_changed_) tops_changed_.add(static_cast<std::uint32_t>(c));
  }
  ColumnSet fell_, dirty_, scan_;  ///< scratch of transfer(), wake(), recompute_tops()
  /// what transfer() does to each hot grain, decided before any is done
  enum class Fate : std::uint8_t { Stays, Freed, Trapped, Dislodged, Sleeps };
  std::vector<Fate> fate_;
  /// Whether the tops follow the store (before it changes).
  bool tops_follow(const StaticStore& st) const { return tops_of_ == st.size(); }
  /// Recomputes the tops of the marked columns from the static grains (filed by column).
  void recompute_tops(const HeightField& hf, const StaticStore& st, const ColumnSet& dirty);
  /// Moves the static grains in `slots` (in any order, repeats allowed) to the hot grains as
  /// INTERFACE, in slot order, each added to `changes`; returns how many. With `above_h_free`,
  /// those whose centre lies above h + margin go ACTIVE.
  std::int64_t wake(const HeightField& hf, Grains& hot, StaticStore& st,
                    std::vector<std::uint32_t> slots, std::vector<StateChange>& changes,
                    bool above_h_free);

  StaticReach reach_;  ///< the static grains near a point, for wake_within_reach
};

}  // namespace sandflow

// Wall-clock timing of the stages of a step, printed by --profile.
#pragma once

#include <array>
#include <chrono>
#include <string_view>

namespace sandflow {

class Stopwatch {
 public:
  Stopwatch() : start_(Clock::now()) {}
  double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
  void reset() { start_ = Clock::now(); }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
};

/// The stages of a step, in the order World::step runs them (docs/design.md §1).
enum class Stage {
  Guards,       ///< the checks that stop a run (non-finite grains, grains outside the domain, the
                ///< overlap limit; the assertions of the test builds), the removal of the grains
                ///< that left, and of the solids whose time has come
  Emit,         ///< the emitters' new grains
  HeightField,  ///< (surface mode, each update) H measured, the columns where grains move the
                ///< pile, h evolved through the BCRE exchange
  Impacts,      ///< (surface mode, each update) the static top held below the grains that move
                ///< the pile
  Transfer,     ///< (surface mode) trap, dislodge, sleep, wake: changes of state the DEM applies
  Reach,        ///< (surface mode) the invariant of the layers, before each rebuild of the lists
  Neighbours,   ///< the rebuilds of the pair, wall and boundary lists
  Forces,       ///< the contact forces and the integration: one fused sweep over the grains
                ///< (dem_solver.cpp), so its time is both, and its name says so
  kCount
};

/// The stage's name in --profile and summary.json's stage_seconds.
inline std::string_view stage_name(Stage s) {
  constexpr std::array<std::string_view, static_cast<std::size_t>(Stage::kCount)> kNames = {
      "guards",   "emit",  "height_field", "impacts",
      "transfer", "reach", "neighbours",   "forces+integration"};
  const auto k = static_cast<std::size_t>(s);
  return k < kNames.size() ? kNames[k] : "?";
}

struct Profile {
  std::array<double, static_cast<int>(Stage::kCount)> seconds{};
  double& operator[](Stage s) { return seconds[static_cast<int>(s)]; }
  double operator[](Stage s) const { return seconds[static_cast<int>(s)]; }
};

/// Adds the lifetime of the scope to one stage of a Profile.
class ScopedStage {
 public:
  ScopedStage(Profile& p, Stage s) : p_(p), s_(s) {}
  ~ScopedStage() { p_[s_] += w_.seconds(); }
  ScopedStage(const ScopedStage&) = delete;
  ScopedStage& operator=(const ScopedStage&) = delete;

 private:
  Profile& p_;
  Stage s_;
  Stopwatch w_;
};

/// Runs f() as a part of stage s of p.
template <class F>
void timed(Profile& p, Stage s, F&& f) {
  ScopedStage scope(p, s);
  f();
}

}  // namespace sandflow

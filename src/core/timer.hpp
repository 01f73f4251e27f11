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

/// Forces covers the contact forces and the integration, done in one sweep (dem_solver.cpp);
/// Surface the height-field updates and the transfers through the interface; Reach the invariant
/// of the layers, held before each rebuild of the pair list (static grains within reach woken).
enum class Stage { Emit, Surface, Reach, Neighbours, Forces, kCount };

inline std::string_view stage_name(Stage s) {
  switch (s) {
    case Stage::Emit: return "emit";
    case Stage::Surface: return "surface";
    case Stage::Reach: return "reach";
    case Stage::Neighbours: return "neighbours";
    case Stage::Forces: return "forces";
    default: return "?";
  }
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

}  // namespace sandflow

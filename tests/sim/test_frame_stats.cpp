// The simulated fraction that compare.json reports (sim/world.hpp).
#include <gtest/gtest.h>

#include <vector>

#include "sim/world.hpp"

namespace {

sandflow::FrameStats frame(std::int64_t total, std::int64_t active, std::int64_t interface) {
  sandflow::FrameStats f;
  f.n_total = total;
  f.n_active = active;
  f.n_interface = interface;
  f.n_static = total - active - interface;
  return f;
}

}  // namespace

// A pour: the grains that are in at each frame weigh by their number, so the fraction is the share
// of plain DEM's grain work (grain-frames) the surface run does, not the mean of the frames'.
TEST(SimulatedFraction, IsSimulatedGrainFramesOverAllGrainFrames) {
  const std::vector<sandflow::FrameStats> frames = {frame(0, 0, 0), frame(10, 10, 0),
                                                    frame(100, 20, 10), frame(300, 30, 30)};
  EXPECT_DOUBLE_EQ(sandflow::simulated_fraction(frames), 100.0 / 410.0);
  // the last half: frames 2 and 3 (the mean of their fractions would be 0.25)
  EXPECT_DOUBLE_EQ(sandflow::simulated_fraction(frames, frames.size() / 2), 90.0 / 400.0);
  // without grains nothing is saved
  EXPECT_DOUBLE_EQ(sandflow::simulated_fraction(std::vector<sandflow::FrameStats>{frame(0, 0, 0)}),
                   1.0);
  EXPECT_DOUBLE_EQ(sandflow::simulated_fraction(frames, frames.size()), 1.0);
}

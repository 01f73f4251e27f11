// Emitters on the sizes a user may give: what they place, and that an absurd size is refused at
// once instead of making (or looping over) a pattern no machine holds.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/error.hpp"
#include "scene/emitters.hpp"

namespace sandflow {
namespace {

MaterialConfig millimetre_grains() {
  MaterialConfig m;
  m.diameter = 0.001;
  m.diameter_spread = 0.0;
  return m;
}

EmitterConfig block(Vec3 center, Vec3 size, std::int64_t count) {
  EmitterConfig e;
  e.type = EmitterType::Block;
  e.center = center;
  e.size = size;
  e.count = count;
  e.jitter = 0;
  return e;
}

const Vec3 kGravity{0, 0, -9.81};

TEST(Emitters, ABlockFarLargerThanItsCountPlacesExactlyTheCountFromItsLowCorner) {
  // a 100 m box of 10 one-millimetre grains: 10^15 lattice points, of which the first 10 are used
  const EmitterConfig e = block({0, 0, 50}, {100, 100, 100}, 10);
  Emitter emitter(e, millimetre_grains(), kGravity, "test");
  Rng rng(1);
  std::vector<NewGrain> out;
  emitter.emit(0.0, rng, out);
  ASSERT_EQ(out.size(), 10u);
  EXPECT_TRUE(emitter.done());
  const Real s = e.spacing * 0.001;
  for (std::size_t i = 0; i < out.size(); ++i) {
    // one row along x at the box's low corner, a spacing apart (jitter 0)
    EXPECT_NEAR(out[i].x.x, -50 + 0.0005 + static_cast<Real>(i) * s, 1e-9) << i;
    EXPECT_NEAR(out[i].x.y, -50 + 0.0005, 1e-12);
    EXPECT_NEAR(out[i].x.z, 0.0005, 1e-12);
    EXPECT_DOUBLE_EQ(out[i].r, 0.0005);
  }
}

TEST(Emitters, ALatePourBatchIsWhereAndAsFastAsFreeFallSinceItsTimeMakesIt) {
  // a batch may wait for the pair list's next rebuild; its grains must not notice
  EmitterConfig pour;
  pour.type = EmitterType::Pour;
  pour.center = {0, 0, 0.5};
  pour.radius = 0.01;
  pour.count = 1000;
  pour.rate = 50000;  // about 35 grains a batch
  pour.velocity = {0.2, 0, -1.5};
  pour.jitter = 0.5;
  Emitter on_time(pour, millimetre_grains(), kGravity, "test");
  Emitter late(pour, millimetre_grains(), kGravity, "test");
  ASSERT_GT(late.max_wait(), 0.0);
  const Real t0 = late.next_time(), tau = 0.9 * late.max_wait();
  Rng rng_a(7), rng_b(7);
  std::vector<NewGrain> a, b;
  on_time.emit(t0, rng_a, a);
  late.emit(t0 + tau, rng_b, b);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 0u);
  const Vec3 shift = pour.velocity * tau + kGravity * (tau * tau / 2);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_LT(norm(b[i].x - (a[i].x + shift)), 1e-12) << i;
    EXPECT_LT(norm(b[i].v - (a[i].v + kGravity * tau)), 1e-12) << i;
    EXPECT_EQ(a[i].r, b[i].r);
    EXPECT_TRUE(late.near_slots(b[i].x, b[i].r));  // the slot check sees where it lands
  }
  EXPECT_EQ(on_time.next_time(), late.next_time());  // the schedule does not slip
}

TEST(Emitters, ABoxTooSmallForItsCountIsRefusedWithWhatItHolds) {
  // 3 x 3 x 3 slots at 1.05 mm in a 3.2 mm box
  const EmitterConfig e = block({0, 0, 1}, {0.0032, 0.0032, 0.0032}, 28);
  try {
    Emitter emitter(e, millimetre_grains(), kGravity, "s.toml: emitter[0]");
    FAIL() << "no error";
  } catch (const InputError& err) {
    EXPECT_NE(std::string(err.what()).find("the box holds only 27 grains"), std::string::npos)
        << err.what();
  }
  EXPECT_NO_THROW(Emitter(block({0, 0, 1}, {0.0032, 0.0032, 0.0032}, 27), millimetre_grains(),
                          kGravity, "s.toml: emitter[0]"));
}

TEST(Emitters, ImpossibleSizesAreNamedByTheirKeyBeforeAnythingIsMade) {
  EmitterConfig pour;
  pour.type = EmitterType::Pour;
  pour.center = {0, 0, 0.5};
  pour.count = 10;
  pour.radius = 1000;  // a disk 2 km across of 1 mm grains: about 3.3e12 slots
  auto problem = emitter_problem(pour, millimetre_grains());
  ASSERT_TRUE(problem);
  EXPECT_STREQ(problem->key, "radius");
  EXPECT_NE(problem->what.find("more than the limit of 16777216"), std::string::npos)
      << problem->what;
  pour.radius = 1.0;  // 3.3 million slots: allowed
  EXPECT_FALSE(emitter_problem(pour, millimetre_grains()));

  // beyond 2^40 spacings from the origin, x += spacing stops moving x
  EmitterConfig far = block({1.7e308, 0, 1}, {0.01, 0.01, 0.01}, 10);
  problem = emitter_problem(far, millimetre_grains());
  ASSERT_TRUE(problem);
  EXPECT_STREQ(problem->key, "center");
  far.center = {1.0e10, 0, 1};  // 10^13 spacings out: refused
  EXPECT_TRUE(emitter_problem(far, millimetre_grains()));
  far.center = {1.0e6, 0, 1};  // 10^9 spacings out: placed exactly enough
  EXPECT_FALSE(emitter_problem(far, millimetre_grains()));

  // a box thinner than a grain on one side holds nothing, whatever its other sides
  problem = emitter_problem(block({0, 0, 50}, {0.0005, 100, 100}, 10), millimetre_grains());
  ASSERT_TRUE(problem);
  EXPECT_STREQ(problem->key, "size");
  EXPECT_THROW(Emitter(block({0, 0, 50}, {0.0005, 100, 100}, 10), millimetre_grains(), kGravity,
                       "test"),
               InputError);
}

}  // namespace
}  // namespace sandflow

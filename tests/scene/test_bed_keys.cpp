// The keys of a bed emitter: a bed loads with the count of its packing, and its bad input gives
// the usual FILE:LINE:COLUMN message (count given, height missing, another type's key, no floor,
// no room, more grains than the limit, an empty footprint).
#include <gtest/gtest.h>

#include <string>

#include "scene/scene_loader.hpp"
#include "support/scene_errors.hpp"

namespace sandflow {
namespace {

using test::expect_error;

// 2 cm grains in a 16 cm box container, the bed filling its inside 8 cm deep
const std::string kBox =
    "[material]\n"
    "diameter = 0.02\n"
    "[[geometry]]\n"
    "type = \"box\"\n"
    "container = true\n"
    "center = [0, 0, 0.1]\n"
    "size = [0.16, 0.16, 0.2]\n";

std::string bed(const std::string& keys) {
  return kBox + "[[emitter]]\ntype = \"bed\"\ncenter = [0, 0, 0]\n" + keys;
}

TEST(BedKeys, ABedLoadsWithTheCountOfItsPacking) {
  const SceneConfig c =
      load_scene_from_string(bed("size = [0.16, 0.16, 0]\nheight = 0.08\n"), "t.toml");
  ASSERT_EQ(c.emitters.size(), 1u);
  const EmitterConfig& e = c.emitters[0];
  EXPECT_EQ(e.type, EmitterType::Bed);
  // 8 x 8 x 4 d^3 at a packing fraction about 0.5 (walls and top loosen its edges), d = 2 cm
  EXPECT_GT(e.count, 200);
  EXPECT_LT(e.count, 300);
  EXPECT_EQ(c.total_grains(), e.count);
  EXPECT_NEAR(e.center.z - e.size.z / 2, 0, 1e-9);     // from the container's floor
  EXPECT_LE(e.center.z + e.size.z / 2, 0.08 + 1e-12);  // up to its top
  // the same scene, the same bed; another seed, another packing
  EXPECT_EQ(load_scene_from_string(bed("size = [0.16, 0.16, 0]\nheight = 0.08\n"), "t.toml")
                .emitters[0]
                .count,
            e.count);
}

TEST(BedKeys, CountIsNotAKeyOfABed) {
  expect_error(bed("size = [0.16, 0.16, 0]\nheight = 0.08\ncount = 100\n"),
               {"t.toml:13:1: emitter[0].count is not a key of a bed",
                "follow from its region (center, size, height"});
}

TEST(BedKeys, HeightIsRequired) {
  expect_error(bed("size = [0.16, 0.16, 0]\n"), {"emitter[0].height is missing", "flat top"});
}

TEST(BedKeys, KeysOfOtherEmittersAreRefused) {
  expect_error(
      bed("size = [0.16, 0.16, 0]\nheight = 0.08\nvelocity = [0, 0, 1]\n"),
      {"t.toml:13:1:",
       "velocity is not a key of a bed emitter (keys: type, name, start, center, size, height, "
       "relief, relief_wavelength, relief_seed)"});
}

TEST(BedKeys, ANegativeReliefIsRefused) {
  expect_error(bed("size = [0.16, 0.16, 0]\nheight = 0.08\nrelief = -0.01\n"),
               {"t.toml:13:", "emitter[0].relief"});
  expect_error(bed("size = [0.16, 0.16, 0]\nheight = 0.08\nrelief = 0.02\nrelief_wavelength = 0\n"),
               {"t.toml:14:", "emitter[0].relief_wavelength"});
}

TEST(BedKeys, AnEmptyFootprintIsRefused) {
  expect_error(bed("size = [0, 0.16, 0]\nheight = 0.08\n"), {"t.toml:11:", "emitter[0].size"});
  // narrower than a grain
  expect_error(bed("size = [0.01, 0.16, 0]\nheight = 0.08\n"),
               {"t.toml:11:1: emitter[0].size is 0.01 m along x, less than the largest grain"});
}

TEST(BedKeys, ABedNeedsAFloorUnderItsFootprint) {
  // the footprint reaches past the container: nothing under its corner
  expect_error(bed("size = [0.4, 0.4, 0]\nheight = 0.08\n"),
               {"t.toml:10:1: emitter[0].center puts the bed over", "where no solid lies under",
                "a bed rests on the scene's geometry"});
}

TEST(BedKeys, ATopBelowTheFloorHoldsNoGrainAndIsRefused) {
  expect_error(bed("size = [0.16, 0.16, 0]\nheight = 0.01\n"),
               {"t.toml:12:1: emitter[0].height = 0.01 m leaves no room for a grain"});
  // below every solid: nothing to rest on
  expect_error(bed("size = [0.16, 0.16, 0]\nheight = -0.5\n"),
               {"t.toml:10:1: emitter[0].center puts the bed over", "(z = -0.5 m)"});
}

TEST(BedKeys, ABedOfMoreGrainsThanTheLimitIsRefusedBeforeItIsPacked) {
  // a floor plane under a 100 m x 100 m footprint, 10 m deep, of 2 cm grains: 1e5 m^3 at 0.6
  // over 4.2e-6 m^3 a grain, 1.4e10
  expect_error(
      "[material]\ndiameter = 0.02\n[[geometry]]\ntype = \"plane\"\n[[emitter]]\ntype = "
      "\"bed\"\nsize = [100, 100, 0]\nheight = 10\n",
      {"t.toml:7:1: emitter[0].size makes a bed of about 1.43e+10 grains, more than the limit of "
       "2000000000"});
}

}  // namespace
}  // namespace sandflow

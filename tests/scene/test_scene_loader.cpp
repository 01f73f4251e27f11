// Scene loader: values and defaults of a valid scene, and the exact place (name:LINE:COL or
// --set KEY) and key named by each kind of error. Scene texts are built line by line so that the
// expected line and column can be read off the text.

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "scene/scene_loader.hpp"
#include "support/scene_errors.hpp"

namespace sandflow {
namespace {

// The smallest valid scene: one emitter with its required count.
constexpr const char* kMinimal =
    "[[emitter]]\n"
    "count = 100\n";

using test::error_of;
using test::expect_error;

TEST(SceneLoader, MinimalSceneTakesTheDefaults) {
  const SceneConfig c = load_scene_from_string(kMinimal, "scenes/floor.toml");
  EXPECT_EQ(c.path, "scenes/floor.toml");
  EXPECT_EQ(c.name, "floor");  // the file stem when [scene] has no name
  // Missing keys take the struct defaults (the documented defaults of docs/scenes.md).
  const MaterialConfig m;
  const SimulationConfig s;
  EXPECT_EQ(c.material.density, m.density);
  EXPECT_EQ(c.material.restitution, m.restitution);
  EXPECT_EQ(c.material.friction, m.friction);
  EXPECT_EQ(c.simulation.mode, s.mode);
  EXPECT_EQ(c.simulation.gravity, Vec3(0, 0, -9.81));
  EXPECT_EQ(c.simulation.dt_fraction, s.dt_fraction);
  EXPECT_FALSE(c.simulation.dt.has_value());
  EXPECT_EQ(c.output.fps, OutputConfig{}.fps);
  EXPECT_FALSE(c.output.duration.has_value());
  EXPECT_TRUE(c.geometry.empty());
  ASSERT_EQ(c.emitters.size(), 1u);
  EXPECT_EQ(c.emitters[0].name, "emitter 0");
  EXPECT_EQ(c.emitters[0].type, EmitterType::Pour);
  EXPECT_EQ(c.emitters[0].shape, PourShape::Disk);
  EXPECT_EQ(c.emitters[0].count, 100);
  EXPECT_EQ(c.emitters[0].rate, EmitterConfig{}.rate);
  EXPECT_EQ(c.total_grains(), 100);
}

TEST(SceneLoader, FullSceneReadsEveryTable) {
  const std::string text =
      "[scene]\n"
      "name = \"pour\"\n"
      "description = \"a pour onto a floor\"\n"
      "[material]\n"
      "density = 2500\n"  // an integer where a float is expected
      "diameter = 0.004\n"
      "restitution = 0.5\n"
      "friction = 0.7\n"
      "twisting_friction = 0.05\n"
      "wall_twisting_friction = 0.08\n"
      "[simulation]\n"
      "mode = \"dem\"\n"
      "gravity = [0, 0, -10]\n"
      "dt = 1e-5\n"
      "seed = 42\n"
      "threads = 2\n"
      "[output]\n"
      "fps = 60\n"
      "duration = 4.5\n"
      "[[geometry]]\n"
      "type = \"plane\"\n"
      "normal = [0, 0, 2]\n"
      "render = \"glass\"\n"
      "[[geometry]]\n"
      "type = \"box\"\n"
      "name = \"bin\"\n"
      "size = [1, 2, 0.5]\n"
      "rotation = [0, 0, 45]\n"
      "container = true\n"
      "[[emitter]]\n"
      "type = \"pour\"\n"
      "shape = \"rect\"\n"
      "count = 1e4\n"  // an integral float where an integer is expected
      "size = [0.2, 0.1, 0]\n"
      "rate = 500\n"
      "[[emitter]]\n"
      "type = \"block\"\n"
      "count = 8\n"
      "velocity = [3, 0, 0]\n";
  const SceneConfig c = load_scene_from_string(text, "scenes/x.toml");
  EXPECT_EQ(c.name, "pour");
  EXPECT_EQ(c.description, "a pour onto a floor");
  EXPECT_EQ(c.material.density, 2500.0);
  EXPECT_EQ(c.material.diameter, 0.004);
  EXPECT_EQ(c.material.friction, 0.7);
  EXPECT_EQ(c.material.k_n, MaterialConfig{}.k_n);
  EXPECT_EQ(c.material.twisting_friction, 0.05);
  EXPECT_EQ(c.material.wall_twisting_friction, 0.08);
  EXPECT_EQ(MaterialConfig{}.twisting_friction, 0.0);  // none unless asked for
  EXPECT_EQ(c.simulation.mode, Mode::Dem);
  EXPECT_EQ(c.simulation.gravity, Vec3(0, 0, -10));
  ASSERT_TRUE(c.simulation.dt.has_value());
  EXPECT_EQ(*c.simulation.dt, 1e-5);
  EXPECT_EQ(c.simulation.seed, 42u);
  EXPECT_EQ(c.simulation.threads, 2);
  EXPECT_EQ(c.output.fps, 60.0);
  ASSERT_TRUE(c.output.duration.has_value());
  EXPECT_EQ(*c.output.duration, 4.5);

  ASSERT_EQ(c.geometry.size(), 2u);
  EXPECT_EQ(c.geometry[0].type, GeometryType::Plane);
  EXPECT_EQ(c.geometry[0].name, "geometry 0");
  EXPECT_EQ(c.geometry[0].normal, Vec3(0, 0, 1));  // normalised
  EXPECT_EQ(c.geometry[0].render, RenderStyle::Glass);
  EXPECT_EQ(c.geometry[1].type, GeometryType::Box);
  EXPECT_EQ(c.geometry[1].name, "bin");
  EXPECT_EQ(c.geometry[1].size, Vec3(1, 2, 0.5));
  EXPECT_EQ(c.geometry[1].rotation_deg, Vec3(0, 0, 45));
  EXPECT_TRUE(c.geometry[1].container);

  ASSERT_EQ(c.emitters.size(), 2u);
  EXPECT_EQ(c.emitters[0].shape, PourShape::Rect);
  EXPECT_EQ(c.emitters[0].count, 10000);
  EXPECT_EQ(c.emitters[0].rate, 500.0);
  EXPECT_EQ(c.emitters[1].type, EmitterType::Block);
  EXPECT_EQ(c.emitters[1].name, "emitter 1");
  EXPECT_EQ(c.emitters[1].velocity, Vec3(3, 0, 0));
  EXPECT_EQ(c.total_grains(), 10008);
}

TEST(SceneLoader, OutOfRangeValueGivesTheDocumentedMessage) {
  const std::string text =
      "[material]\n"
      "  restitution = 1.4\n" +
      std::string(kMinimal);
  EXPECT_EQ(error_of(text), "t.toml:2:3: material.restitution = 1.4 is outside (0, 1]");
}

// Errors found after loading, about keys checked together, are placed as the loader's own: at the
// line of the first key named that the scene gave, at an override's --set, or at a table's first
// key; a scene without any of them is named by its file.
TEST(SceneLoader, KeysKeepTheirPlacesForLaterErrors) {
  const std::string text =
      "[material]\ndensity = 2000\n  k_n = 5e4\n[[emitter]]\nrate = 10\ncount = 100\n";
  const SceneConfig c = load_scene_from_string(text, "t.toml", {{"material.friction", "0.4"}});
  EXPECT_EQ(c.place({"material.k_n"}), "t.toml:3:3");
  EXPECT_EQ(c.place({"material.diameter", "material.density"}), "t.toml:2:1");  // the first given
  EXPECT_EQ(c.place({"material.friction"}), "--set material.friction");
  EXPECT_EQ(c.place({"emitter[0]"}), "t.toml:5:1");  // the table: its first key
  EXPECT_EQ(c.place({"emitter[0].count"}), "t.toml:6:1");
  EXPECT_EQ(c.place({"simulation.dt", "output"}), "t.toml");
}

// Keys the scene gives but nothing uses, and angles that read like radians, are warnings at their
// lines. A --set that makes a key unused (compare --equal-stiffness sets from_load = false) is
// asked for knowingly and warns of nothing.
TEST(SceneLoader, UnusedKeysAndAnglesLikeRadiansAreWarnedOf) {
  const std::string text =
      "[simulation]\ndt = 1e-5\ndt_fraction = 0.05\n"
      "[stiffness]\nfrom_load = false\nimpact_speed = 2\nimpact_overlap = 0.2\n"
      "[surface]\nrepose_angle = 0.6\nmax_angle = 40\n[camera]\nfov = 1\n" +
      std::string(kMinimal);
  const SceneConfig c = load_scene_from_string(text, "t.toml");
  const std::vector<std::string> expected = {
      "t.toml:3:1: simulation.dt_fraction is not used: simulation.dt is given",
      "t.toml:6:1: stiffness.impact_speed is not used: stiffness.from_load = false takes k_n from "
      "material.k_n",
      "t.toml:9:1: surface.repose_angle = 0.6 is in degrees, a heap all but flat; if it was meant "
      "in radians, write 34.38",
      "t.toml:12:1: camera.fov = 1 is in degrees, a view through a keyhole; if it was meant in "
      "radians, write 57.3"};
  EXPECT_EQ(c.warnings, expected);
  // (impact_overlap is still the limit compare holds the overlaps to: no warning; nor for 40)

  const std::string quiet =
      "[simulation]\ndt_fraction = 0.05\n[stiffness]\nimpact_speed = 2\n" + std::string(kMinimal);
  EXPECT_TRUE(load_scene_from_string(quiet, "t.toml",
                                     {{"simulation.dt", "1e-5"}, {"stiffness.from_load", "false"}})
                  .warnings.empty());
  EXPECT_TRUE(load_scene_from_string(kMinimal, "t.toml").warnings.empty());
}

// A name goes into the comments and headers of exported files: a line break in it ended a POV-Ray
// comment and started code (#debug, #fopen). The scene's name makes the default output folder:
// one with / or .. put it outside out/.
TEST(SceneLoader, NamesAreOneLineAndTheScenesNameMakesAFolder) {
  expect_error("[scene]\nname = \"x\\n#debug\"\n" + std::string(kMinimal),
               {"t.toml:2:1: scene.name = \"x\\u000a#debug\" holds a control character"});
  expect_error("[[geometry]]\ntype = \"plane\"\nname = \"a\\tb\"\n" + std::string(kMinimal),
               {"geometry[0].name", "holds a control character"});
  expect_error(std::string(kMinimal) + "name = \"e\\u007f\"\n",
               {"emitter[0].name", "holds a control character"});
  for (const char* name : {"../../zz", "x/y", "", "..", "a\\\\b"})
    expect_error("[scene]\nname = \"" + std::string(name) + "\"\n" + std::string(kMinimal),
                 {"t.toml:2:1: scene.name = ", "expected a name that can make a folder's"});
  EXPECT_EQ(
      load_scene_from_string("[scene]\nname = \"dune 2, ok\"\n" + std::string(kMinimal), "t.toml")
          .name,
      "dune 2, ok");
}

TEST(SceneLoader, OneSidedRangesSayWhatIsExpected) {
  expect_error("[material]\ndensity = -1\n" + std::string(kMinimal),
               {"t.toml:2:1: material.density = -1 is not > 0"});
  expect_error("[material]\ntwisting_friction = -0.1\n" + std::string(kMinimal),
               {"t.toml:2:1: material.twisting_friction = -0.1 is not >= 0"});
  expect_error("[simulation]\ndt_fraction = 0.5\n" + std::string(kMinimal),
               {"t.toml:2:1: simulation.dt_fraction = 0.5 is outside (0, 0.2]"});
  expect_error("[[emitter]]\ncount = 100\njitter = 1.5\n",
               {"t.toml:3:1: emitter[0].jitter = 1.5 is outside [0, 1]"});
}

// A pour's area faces up (it lies level) unless it faces its velocity (a nozzle), which it needs
// to have; only a pour has the key.
TEST(SceneLoader, APourFacesUpOrAlongItsVelocity) {
  const std::string pour = "[[emitter]]\ntype = \"pour\"\ncount = 10\n";
  EXPECT_EQ(load_scene_from_string(pour, "t.toml").emitters[0].facing, PourFacing::Up);
  const SceneConfig nozzle =
      load_scene_from_string(pour + "facing = \"velocity\"\nvelocity = [1, 0, 0]\n", "t.toml");
  EXPECT_EQ(nozzle.emitters[0].facing, PourFacing::Velocity);
  expect_error(pour + "facing = \"velocity\"\n",
               {"t.toml:4:1: emitter[0].facing = \"velocity\" lays the area across the velocity, "
                "but velocity is zero"});
  expect_error(pour + "facing = \"sideways\"\n",
               {"t.toml:4:1: emitter[0].facing = \"sideways\" is not one of \"up\", \"velocity\""});
  expect_error("[[emitter]]\ntype = \"block\"\ncount = 10\nfacing = \"up\"\n",
               {"t.toml:4:1: emitter[0].facing is not a key of a block emitter"});
}

TEST(SceneLoader, UnknownKeyIsNamedWithItsPlace) {
  const std::string text =
      "[material]\n"
      "density = 2500\n"
      "densty = 2400\n" +
      std::string(kMinimal);
  expect_error(text,
               {"t.toml:3:1: material.densty is not a key of [material]", "density, diameter"});
}

TEST(SceneLoader, UnknownTopLevelTableIsAnError) {
  const std::string text = std::string(kMinimal) +
                           "[materail]\n"
                           "density = 2500\n";
  expect_error(text, {"t.toml:3:2: materail is not a key of a scene file"});
}

TEST(SceneLoader, WrongTypeSaysWhatWasExpected) {
  expect_error("[material]\n  friction = \"high\"\n" + std::string(kMinimal),
               {"t.toml:2:3: material.friction: expected a number, got a string"});
  expect_error("material = 5\n" + std::string(kMinimal),
               {"t.toml:1:1: material: expected a table"});
  expect_error("[[emitter]]\ncount = 2.5\n",
               {"t.toml:2:1: emitter[0].count: expected an integer, got 2.5"});
  expect_error("[simulation]\nmode = \"fast\"\n" + std::string(kMinimal),
               {"t.toml:2:1: simulation.mode = \"fast\" is not one of \"surface\", \"dem\""});
}

TEST(SceneLoader, NonFiniteNumbersAreRefused) {
  // Column 18 is the nan inside the array: the element is named, with its index.
  expect_error("[simulation]\ngravity = [0, 0, nan]\n" + std::string(kMinimal),
               {"t.toml:2:18: simulation.gravity[2] = nan is not a finite number"});
  expect_error("[simulation]\ndt = inf\n" + std::string(kMinimal),
               {"t.toml:2:1: simulation.dt = inf is not a finite number"});
  expect_error("[[emitter]]\ncount = -inf\n",
               {"t.toml:2:1: emitter[0].count = -inf is not a finite number"});
}

TEST(SceneLoader, SyntaxErrorGivesPlaceAndDescription) {
  expect_error("[material]\ndensity = 2600\nfriction = = 0.5\n",
               {"t.toml:3:12: ", "could not determine value type"});
}

TEST(SceneLoader, SceneWithoutEmitterIsRefused) {
  expect_error("[material]\ndensity = 2600\n",
               {"t.toml:1:1: emitter: a scene needs at least one [[emitter]]"});
  expect_error("# no emitters\nemitter = []\n",
               {"t.toml:2:1: emitter: a scene needs at least one [[emitter]]"});
  expect_error("[[emitter]]\ntype = \"pour\"\n", {"t.toml:1:1: emitter[0].count is missing"});
}

TEST(SceneLoader, VectorsNeedExactlyThreeNumbers) {
  expect_error("[simulation]\ngravity = [0, -9.81]\n" + std::string(kMinimal),
               {"t.toml:2:1: simulation.gravity: expected an array of 3 numbers, got 2 elements"});
  expect_error("[simulation]\ngravity = [0, \"0\", 1]\n" + std::string(kMinimal),
               {"t.toml:2:15: simulation.gravity[1]: expected a number, got a string"});
  expect_error("[simulation]\ngravity = -9.81\n" + std::string(kMinimal),
               {"t.toml:2:1: simulation.gravity: expected an array of 3 numbers, got a float"});
}

TEST(SceneLoader, KeysOfAnotherTypeAreRefused) {
  const std::string text = std::string(kMinimal) +
                           "[[geometry]]\n"
                           "type = \"box\"\n"
                           "[[geometry]]\n"
                           "type = \"plane\"\n"
                           "  radius = 0.5\n";
  expect_error(text, {"t.toml:7:3: geometry[1].radius is not a key of a plane", "point, normal"});
  expect_error("[[emitter]]\ncount = 5\nshape = \"disk\"\nsize = [1, 1, 1]\n",
               {"t.toml:4:1: emitter[0].size is not a key of a pour with shape = \"disk\""});
  expect_error("[[emitter]]\ntype = \"block\"\ncount = 5\nrate = 10\n",
               {"t.toml:4:1: emitter[0].rate is not a key of a block emitter"});
}

TEST(SceneLoader, AbsurdCountIsRefusedWithTheLimit) {
  expect_error("[[emitter]]\ncount = 5000000000\n",
               {"t.toml:2:1: emitter[0].count = 5000000000 is outside [1, 2000000000]"});
  expect_error("[[emitter]]\ncount = 0\n", {"t.toml:2:1: emitter[0].count = 0 is outside [1, "});
}

TEST(SceneLoader, GeometryChecks) {
  expect_error(std::string(kMinimal) + "[[geometry]]\nnormal = [0, 0, 0]\n",
               {"t.toml:4:1: geometry[0].normal = [0, 0, 0]: expected a non-zero normal"});
  expect_error(std::string(kMinimal) + "[[geometry]]\ntype = \"box\"\nsize = [1, -2, 1]\n",
               {"t.toml:5:12: geometry[0].size[1] = -2 is not > 0"});
  expect_error(std::string(kMinimal) + "[[geometry]]\ntype = \"cone\"\n",
               {"t.toml:4:1: geometry[0].type = \"cone\" is not one of \"plane\", \"box\""});
}

TEST(SceneLoader, OverridesApplyBeforeValidation) {
  const std::string text =
      std::string(kMinimal) + "[material]\nfriction = 0.5\n[simulation]\nmode = \"dem\"\n";
  const SceneConfig c =
      load_scene_from_string(text, "t.toml",
                             {{"material.friction", "0.9"},
                              {"simulation.mode", "surface"},  // a bare word is taken as a string
                              {"simulation.gravity", "[0, 0, -1]"},
                              {"emitter[0].rate", "50"},
                              {"emitter.0.count", "7"},
                              {"output.fps", "60"}});  // [output] is not in the file: created
  EXPECT_EQ(c.material.friction, 0.9);
  EXPECT_EQ(c.simulation.mode, Mode::Surface);
  EXPECT_EQ(c.simulation.gravity, Vec3(0, 0, -1));
  EXPECT_EQ(c.emitters[0].rate, 50.0);
  EXPECT_EQ(c.emitters[0].count, 7);
  EXPECT_EQ(c.output.fps, 60.0);
}

TEST(SceneLoader, OverriddenValuesAreValidatedAndNamed) {
  const std::string text = std::string(kMinimal) + "[material]\nrestitution = 0.5\n";
  EXPECT_EQ(error_of(text, {{"material.restitution", "1.4"}}),
            "--set material.restitution: material.restitution = 1.4 is outside (0, 1]");
  expect_error(text, {"--set simulation.gravity: simulation.gravity[2] = nan is not a finite"},
               {{"simulation.gravity", "[0, 0, nan]"}});
  expect_error(text,
               {"--set emitter[0].count: emitter[0].count: expected an integer, got a string"},
               {{"emitter[0].count", "many"}});
  // a number past a double's range is not read as the word "1e400" (which said "got a string")
  expect_error(text,
               {"--set material.restitution: the value 1e400 is beyond the range of a double"},
               {{"material.restitution", "1e400"}});
}

TEST(SceneLoader, OverrideOfUnknownKeyOrMissingTableIsAnError) {
  expect_error(kMinimal, {"--set material.frction: material.frction is not a key of [material]"},
               {{"material.frction", "0.5"}});
  expect_error(kMinimal, {"--set emitter.5.rate: ", "emitter[5]", "(it has 1)"},
               {{"emitter.5.rate", "10"}});
  expect_error(kMinimal, {"--set materail.friction: the scene has no table materail"},
               {{"materail.friction", "0.5"}});
  expect_error(kMinimal, {"--set geometry.0.radius: the scene has no table geometry"},
               {{"geometry.0.radius", "1"}});
  expect_error(kMinimal, {"--set emitter..rate: malformed key"}, {{"emitter..rate", "1"}});
}

TEST(SceneLoader, DefaultModeIsSurface) {
  EXPECT_EQ(SimulationConfig{}.mode, Mode::Surface);
  EXPECT_EQ(load_scene_from_string(kMinimal, "t.toml").simulation.mode, Mode::Surface);
}

TEST(SceneLoader, StiffnessAndSurfaceAreUnsetByDefault) {
  const SceneConfig c = load_scene_from_string(kMinimal, "t.toml");
  EXPECT_FALSE(c.stiffness.from_load);
  EXPECT_EQ(c.stiffness.max_overlap, 0.01);
  EXPECT_EQ(c.stiffness.impact_overlap, 0.1);
  EXPECT_FALSE(c.stiffness.impact_speed.has_value());
  EXPECT_FALSE(c.stiffness.dem_depth.has_value());
  EXPECT_FALSE(c.stiffness.surface_depth.has_value());
  EXPECT_DOUBLE_EQ(c.surface.repose_angle, deg_to_rad(32.0));
  EXPECT_FALSE(c.surface.cell_size.has_value());
  EXPECT_FALSE(c.surface.max_angle.has_value());
  EXPECT_FALSE(c.surface.extent.has_value());
}

TEST(SceneLoader, StiffnessTableIsRead) {
  const std::string text =
      "[stiffness]\n"
      "from_load = true\n"
      "max_overlap = 0.02\n"
      "impact_overlap = 0.5\n"  // the upper bound is allowed
      "impact_speed = 0\n"      // so is 0
      "dem_depth = 0.3\n"
      "surface_depth = 0.04\n" +
      std::string(kMinimal);
  const SceneConfig c = load_scene_from_string(text, "t.toml");
  EXPECT_TRUE(c.stiffness.from_load);
  EXPECT_EQ(c.stiffness.max_overlap, 0.02);
  EXPECT_EQ(c.stiffness.impact_overlap, 0.5);
  ASSERT_TRUE(c.stiffness.impact_speed.has_value());
  EXPECT_EQ(*c.stiffness.impact_speed, 0.0);
  ASSERT_TRUE(c.stiffness.dem_depth.has_value());
  EXPECT_EQ(*c.stiffness.dem_depth, 0.3);
  ASSERT_TRUE(c.stiffness.surface_depth.has_value());
  EXPECT_EQ(*c.stiffness.surface_depth, 0.04);
}

TEST(SceneLoader, SurfaceTableIsReadWithAnglesInRadians) {
  const std::string text =
      "[surface]\n"
      "cell_size = 0.012\n"
      "exchange_rate = 25\n"
      "repose_angle = 30\n"
      "max_angle = 30\n"  // equal to the repose angle is allowed
      "rolling_min = 0\n"
      "flowing_min = 0.03\n"
      "flowing_hold = 0.25\n"
      "erosion_reach = 0.007\n"
      "interface_thickness = 0.015\n"
      "update_interval = 0.004\n"
      "trap_speed = 0.05\n"
      "flow_speed = 0.2\n"
      "extent = [-1, -0.5, 1, 2]\n" +
      std::string(kMinimal);
  const SceneConfig c = load_scene_from_string(text, "t.toml");
  const SurfaceConfig& s = c.surface;
  ASSERT_TRUE(s.cell_size && s.exchange_rate && s.max_angle && s.rolling_min && s.flowing_min &&
              s.interface_thickness && s.update_interval && s.trap_speed && s.flow_speed &&
              s.extent);
  EXPECT_EQ(*s.cell_size, 0.012);
  EXPECT_EQ(*s.exchange_rate, 25.0);
  EXPECT_DOUBLE_EQ(s.repose_angle, kPi / 6);
  EXPECT_DOUBLE_EQ(*s.max_angle, kPi / 6);
  EXPECT_EQ(*s.rolling_min, 0.0);
  EXPECT_EQ(*s.flowing_min, 0.03);
  EXPECT_EQ(s.flowing_hold, 0.25);
  ASSERT_TRUE(s.erosion_reach);
  EXPECT_EQ(*s.erosion_reach, 0.007);
  EXPECT_EQ(*s.interface_thickness, 0.015);
  EXPECT_EQ(*s.update_interval, 0.004);
  EXPECT_EQ(*s.trap_speed, 0.05);
  EXPECT_EQ(*s.flow_speed, 0.2);
  EXPECT_EQ(*s.extent, (std::array<Real, 4>{-1, -0.5, 1, 2}));
}

TEST(SceneLoader, BadStiffnessValuesNameTheKey) {
  const std::string k = std::string(kMinimal) + "[stiffness]\n";  // keys go on line 4
  expect_error(k + "from_load = 1\n",
               {"t.toml:4:1: stiffness.from_load: expected true or false, got an integer"});
  expect_error(k + "max_overlap = 0\n",
               {"t.toml:4:1: stiffness.max_overlap = 0 is outside (0, 0.5]"});
  expect_error(k + "max_overlap = 0.6\n", {"stiffness.max_overlap = 0.6 is outside (0, 0.5]"});
  expect_error(k + "impact_overlap = 0.51\n",
               {"t.toml:4:1: stiffness.impact_overlap = 0.51 is outside (0, 0.5]"});
  expect_error(k + "impact_speed = -1\n", {"t.toml:4:1: stiffness.impact_speed = -1 is not >= 0"});
  expect_error(k + "dem_depth = 0\n", {"t.toml:4:1: stiffness.dem_depth = 0 is not > 0"});
  expect_error(k + "surface_depth = -0.1\n",
               {"t.toml:4:1: stiffness.surface_depth = -0.1 is not > 0"});
  expect_error(k + "max_overlaps = 0.1\n",
               {"t.toml:4:1: stiffness.max_overlaps is not a key of [stiffness]", "max_overlap"});
}

TEST(SceneLoader, BadSurfaceValuesNameTheKey) {
  const std::string s = std::string(kMinimal) + "[surface]\n";  // keys go on line 4
  expect_error(s + "cell_size = 0\n", {"t.toml:4:1: surface.cell_size = 0 is not > 0"});
  expect_error(s + "exchange_rate = -2\n", {"t.toml:4:1: surface.exchange_rate = -2 is not > 0"});
  expect_error(s + "repose_angle = 0\n",
               {"t.toml:4:1: surface.repose_angle = 0 is outside (0, 90)"});
  expect_error(s + "repose_angle = 90\n", {"surface.repose_angle = 90 is outside (0, 90)"});
  expect_error(s + "max_angle = 95\n", {"t.toml:4:1: surface.max_angle = 95 is outside (0, 90)"});
  expect_error(s + "rolling_min = -0.01\n",
               {"t.toml:4:1: surface.rolling_min = -0.01 is not >= 0"});
  expect_error(s + "flowing_min = -0.01\n",
               {"t.toml:4:1: surface.flowing_min = -0.01 is not >= 0"});
  expect_error(s + "flowing_hold = -0.5\n",
               {"t.toml:4:1: surface.flowing_hold = -0.5 is not >= 0"});
  expect_error(s + "erosion_reach = -0.001\n",
               {"t.toml:4:1: surface.erosion_reach = -0.001 is not >= 0"});
  expect_error(s + "interface_thickness = 0\n",
               {"t.toml:4:1: surface.interface_thickness = 0 is not > 0"});
  expect_error(s + "update_interval = 0\n", {"t.toml:4:1: surface.update_interval = 0 is not > 0"});
  expect_error(s + "trap_speed = -1\n", {"t.toml:4:1: surface.trap_speed = -1 is not >= 0"});
  expect_error(s + "trap_speed = inf\n", {"surface.trap_speed = inf is not a finite number"});
  expect_error(s + "flow_speed = -0.1\n", {"t.toml:4:1: surface.flow_speed = -0.1 is not >= 0"});
}

TEST(SceneLoader, UnknownSurfaceKeyIsNamed) {
  expect_error(
      std::string(kMinimal) + "[surface]\ncell_size = 0.01\n  cellsize = 0.01\n",
      {"t.toml:5:3: surface.cellsize is not a key of [surface]", "cell_size, exchange_rate"});
}

TEST(SceneLoader, MaxAngleBelowReposeAngleIsRefused) {
  expect_error(std::string(kMinimal) + "[surface]\nrepose_angle = 35\nmax_angle = 30\n",
               {"t.toml:5:1: surface.max_angle = 30 is less than surface.repose_angle = 35"});
  // Against the default repose angle, 32 degrees.
  expect_error(std::string(kMinimal) + "[surface]\nmax_angle = 31.5\n",
               {"t.toml:4:1: surface.max_angle = 31.5 is less than surface.repose_angle = 32 "
                "(the default)"});
}

TEST(SceneLoader, ExtentNeedsFourNumbersInOrder) {
  const std::string s = std::string(kMinimal) + "[surface]\n";
  expect_error(s + "extent = [0, 0, 1]\n",
               {"t.toml:4:1: surface.extent: expected an array of 4 numbers, got 3 elements"});
  expect_error(
      s + "extent = [1, 0, 1, 1]\n",
      {"t.toml:4:1: surface.extent = [1, 0, 1, 1]: expected [x0, y0, x1, y1] with x1 > x0"});
  expect_error(s + "extent = [0, 2, 1, 1]\n", {"t.toml:4:1: surface.extent = [0, 2, 1, 1]"});
  expect_error(s + "extent = [0, 0, nan, 1]\n",
               {"t.toml:4:17: surface.extent[2] = nan is not a finite number"});
  expect_error(s + "extent = 1\n",
               {"t.toml:4:1: surface.extent: expected an array of 4 numbers, got an integer"});
}

TEST(SceneLoader, OverridesReachStiffnessAndSurface) {
  // Neither table is in the file: an override creates it, and its value is checked as usual.
  const SceneConfig c = load_scene_from_string(kMinimal, "t.toml",
                                               {{"surface.repose_angle", "30"},
                                                {"surface.max_angle", "36"},
                                                {"surface.extent", "[0, 0, 2, 1]"},
                                                {"stiffness.from_load", "true"}});
  EXPECT_DOUBLE_EQ(c.surface.repose_angle, deg_to_rad(30.0));
  ASSERT_TRUE(c.surface.max_angle.has_value());
  EXPECT_DOUBLE_EQ(*c.surface.max_angle, deg_to_rad(36.0));
  EXPECT_EQ(c.surface.extent, (std::array<Real, 4>{0, 0, 2, 1}));
  EXPECT_TRUE(c.stiffness.from_load);
  expect_error(kMinimal,
               {"--set surface.repose_angle: surface.repose_angle = 95 is outside (0, 90)"},
               {{"surface.repose_angle", "95"}});
  expect_error(std::string(kMinimal) + "[surface]\nrepose_angle = 35\n",
               {"--set surface.max_angle: surface.max_angle = 30 is less than "
                "surface.repose_angle = 35"},
               {{"surface.max_angle", "30"}});
}

TEST(SceneLoader, ParseOverrideSplitsAtTheFirstEquals) {
  const Override o = parse_override("scene.description = a=b ");
  EXPECT_EQ(o.key, "scene.description");
  EXPECT_EQ(o.value, "a=b");
  EXPECT_THROW(parse_override("abc"), InputError);
  EXPECT_THROW(parse_override("=1"), InputError);
}

TEST(SceneLoader, LoadSceneReadsAFileAndNamesAMissingOne) {
  const std::filesystem::path dir =
      std::filesystem::path(testing::TempDir()) / "sandflow_scene_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "heap.toml").string();
  {
    std::ofstream out(path);
    out << kMinimal << "[material]\nfriction = 0.3\n";
  }
  const SceneConfig c = load_scene(path, {{"material.friction", "0.4"}});
  EXPECT_EQ(c.path, path);
  EXPECT_EQ(c.name, "heap");
  EXPECT_EQ(c.material.friction, 0.4);

  const std::string missing = (dir / "nope.toml").string();
  try {
    load_scene(missing);
    FAIL() << "a missing file must raise InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              missing + ": cannot open the scene file: No such file or directory");
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace sandflow

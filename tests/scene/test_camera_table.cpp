// The [camera] table of a scene file: what it reads, and each error naming file, line and key.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/error.hpp"
#include "scene/scene_loader.hpp"
#include "support/scene_errors.hpp"

namespace sandflow {
namespace {

constexpr const char* kEmitter = "[[emitter]]\ncount = 10\n";  // lines 1-2

using test::error_of;
using test::expect_error;

TEST(CameraTable, DefaultsToTheAutomaticCamera) {
  const SceneConfig s = load_scene_from_string(kEmitter, "t.toml");
  EXPECT_FALSE(s.camera.position);
  EXPECT_FALSE(s.camera.look_at);
  EXPECT_FALSE(s.camera.up);
  EXPECT_DOUBLE_EQ(s.camera.fov_deg, 40.0);
}

TEST(CameraTable, ReadsEveryKey) {
  const SceneConfig s = load_scene_from_string(
      std::string(kEmitter) +
          "[camera]\nposition = [1, -2, 0.5]\nlook_at = [0, 0, 0.1]\nup = [0, 0.1, 1]\nfov = 35\n",
      "t.toml");
  ASSERT_TRUE(s.camera.position && s.camera.look_at && s.camera.up);
  EXPECT_EQ(s.camera.position->y, -2.0);
  EXPECT_EQ(s.camera.look_at->z, 0.1);
  EXPECT_EQ(s.camera.up->y, 0.1);
  EXPECT_EQ(s.camera.fov_deg, 35.0);  // degrees, as written: POV-Ray takes degrees
  // a field of view alone widens the automatic camera
  const SceneConfig fov_only =
      load_scene_from_string(std::string(kEmitter) + "[camera]\nfov = 60\n", "t.toml");
  EXPECT_FALSE(fov_only.camera.position);
  EXPECT_EQ(fov_only.camera.fov_deg, 60.0);
  // --set reaches the table even when the file has none
  const SceneConfig set = load_scene_from_string(kEmitter, "t.toml", {{"camera.fov", "25"}});
  EXPECT_EQ(set.camera.fov_deg, 25.0);
}

TEST(CameraTable, ErrorsNameThePlaceAndWhatWasExpected) {
  const std::string head = std::string(kEmitter) + "[camera]\n";  // the table is line 3
  expect_error(head + "fov = 180\n", {"t.toml:4:1: camera.fov = 180 is outside (0, 180)"});
  expect_error(head + "fov = 0\n", {"t.toml:4:1: camera.fov = 0 is outside (0, 180)"});
  expect_error(head + "position = [1, 2]\nlook_at = [0, 0, 0]\n",
               {"t.toml:4:1: camera.position: expected an array of 3 numbers"});
  expect_error(head + "position = [1, 2, 3]\n",
               {"t.toml:3:1: camera.look_at is missing", "the point the camera"});
  expect_error(head + "look_at = [1, 2, 3]\n", {"t.toml:3:1: camera.position is missing"});
  expect_error(head + "position = [1, 2, 3]\nlook_at = [1, 2, 3]\n",
               {"t.toml:5:1: camera.look_at is camera.position"});
  expect_error(head + "up = [0, 0, 1]\n",
               {"t.toml:4:1: camera.up is set without camera.position and camera.look_at"});
  expect_error(head + "position = [0, 0, 3]\nlook_at = [0, 0, 0]\nup = [0, 0, 1]\n",
               {"t.toml:6:1: camera.up is parallel to the view direction"});
  // without up, the picture's up is z: a camera looking straight down needs one
  expect_error(head + "position = [0, 0, 3]\nlook_at = [0, 0, 0]\n",
               {"t.toml:5:1: camera.look_at is straight above or below camera.position"});
  expect_error(head + "position = [1, 0, 3]\nlook_at = [0, 0, 0]\nup = [0, 0, 0]\n",
               {"t.toml:6:1: camera.up = [0, 0, 0]: expected a direction"});
  // a distance that overflows said "straight above" (it is along x) or "parallel" of an up across
  expect_error(head + "position = [1e160, 0, 0]\nlook_at = [0, 0, 0]\n",
               {"t.toml:5:1: camera.look_at is too far from camera.position"});
  expect_error(head + "position = [1, 0, 0]\nlook_at = [0, 0, 0]\nup = [0, 1e300, 1e300]\n",
               {"t.toml:6:1: camera.up: its length is not a finite number"});
  expect_error(head + "angle = 30\n", {"t.toml:4:1: camera.angle is not a key of [camera]",
                                       "(keys: position, look_at, up, fov)"});
  expect_error(kEmitter, {"--set camera.fov: camera.fov = -3 is outside (0, 180)"},
               {{"camera.fov", "-3"}});
}

}  // namespace
}  // namespace sandflow

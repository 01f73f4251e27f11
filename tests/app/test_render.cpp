// `sandflow render` end to end: the pictures of a tiny run, one camera for all its frames, the
// options it refuses, a frame that fails, a comparison folder, and the movie.
#include <gtest/gtest.h>
#include <png.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "cli_runner.hpp"
#include "core/process.hpp"
#include "io/media_check.hpp"
#include "io/ply.hpp"
#include "io/pov_writer.hpp"
#include "support/memory_cgroup.hpp"
#include "support/small_disk.hpp"

namespace fs = std::filesystem;

namespace {

using sandflow_test::read_text;
using sandflow_test::run_sandflow;
using sandflow_test::Sandbox;
using sandflow_test::tetrahedron_stl;

// 300 grains in a block resting on a floor: three frames take a fraction of a second.
const std::string kRenderScene = sandflow_test::tiny_block_scene(300, 24, 0.08, 0.08);

struct Rgb {
  int width = 0, height = 0;
  std::vector<unsigned char> px;  // row-major RGB, top row first
};

Rgb read_rgb_png(const fs::path& path) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  Rgb out;
  if (!png_image_begin_read_from_file(&img, path.c_str())) return out;
  img.format = PNG_FORMAT_RGB;
  out.px.resize(PNG_IMAGE_SIZE(img));
  if (!png_image_finish_read(&img, nullptr, out.px.data(), 0, nullptr)) {
    png_image_free(&img);
    out.px.clear();
    return out;
  }
  out.width = static_cast<int>(img.width);
  out.height = static_cast<int>(img.height);
  return out;
}

// Standard deviation of the grey level (mean of R, G, B) over the picture [0, 255].
double grey_spread(const Rgb& img) {
  const std::size_t n = img.px.size() / 3;
  double sum = 0, sum2 = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double g = (img.px[3 * i] + img.px[3 * i + 1] + img.px[3 * i + 2]) / 3.0;
    sum += g;
    sum2 += g * g;
  }
  const double mean = sum / static_cast<double>(n);
  return std::sqrt(std::max(0.0, sum2 / static_cast<double>(n) - mean * mean));
}

// Sand is warm (red well above blue); the floor is grey and the sky blue-ish.
int sand_pixels(const Rgb& img) {
  int n = 0;
  for (std::size_t i = 0; i + 2 < img.px.size(); i += 3) n += img.px[i] > img.px[i + 2] + 40;
  return n;
}

// The lines of a .pov scene that must not change between frames: the camera block and the lights.
std::string camera_and_lights(const std::string& pov) {
  const std::size_t a = pov.find("camera {");
  const std::size_t b = pov.find("sky_sphere");
  if (a == std::string::npos || b == std::string::npos) return "";
  return pov.substr(a, b - a);
}

class Render : public ::testing::Test {
 protected:
  void SetUp() override {
    if (sandflow::find_povray().empty()) GTEST_SKIP() << "povray is not installed";
  }
  // A tiny plain-DEM run of `frames` frames in box.dir/run.
  fs::path tiny_run(int frames, const std::string& scene_text = kRenderScene) {
    const auto scene = box.write("tiny.toml", scene_text);
    const auto out = box.dir / "run";
    std::string log;
    EXPECT_EQ(run_sandflow("run " + scene.string() + " --mode dem --frames " +
                               std::to_string(frames) + " --out " + out.string(),
                           &log),
              0)
        << log;
    return out;
  }
  Sandbox box;
};

TEST_F(Render, FramesAreNotBlankAndShareOneCamera) {
  const fs::path run = tiny_run(4);
  std::string log;
  ASSERT_EQ(run_sandflow("render " + run.string() +
                             " --frames 1:3 --width 64 --height 48 --quality draft --keep-pov",
                         &log),
            0)
      << log;
  for (const char* name : {"0001", "0002", "0003"}) {
    const fs::path png = run / "render" / (std::string(name) + ".png");
    const Rgb img = read_rgb_png(png);
    ASSERT_EQ(img.width, 64) << png;
    ASSERT_EQ(img.height, 48) << png;
    // Not blank: the grey level spreads (a one-colour picture has 0; sand, floor and sky give
    // tens of levels) and the grains are in it.
    EXPECT_GT(grey_spread(img), 10.0) << png;
    EXPECT_GT(sand_pixels(img), 50) << png;
    EXPECT_NE(log.find(png.string()), std::string::npos) << log;  // its path printed
  }
  EXPECT_FALSE(fs::exists(run / "render" / "0004.png"));  // only the frames asked for
  // The grains move between frames 1 and 3, the camera and the lights do not.
  const std::string pov1 = read_text(run / "render" / "0001.pov");
  const std::string pov3 = read_text(run / "render" / "0003.pov");
  ASSERT_FALSE(camera_and_lights(pov1).empty()) << pov1.substr(0, 400);
  EXPECT_EQ(camera_and_lights(pov1), camera_and_lights(pov3));
  EXPECT_NE(pov1.substr(pov1.find("// grains")), pov3.substr(pov3.find("// grains")));
  // draft: a point light, no area light
  EXPECT_EQ(pov1.find("area_light"), std::string::npos);
  // the progress line reached the end (stderr is not a terminal here: one plain line)
  EXPECT_NE(log.find("frame 3/3"), std::string::npos) << log;
}

TEST_F(Render, LastFrameByDefaultAndNoLeftovers) {
  const fs::path run = tiny_run(2);
  std::string log;
  ASSERT_EQ(
      run_sandflow("render " + run.string() + " --width 32 --height 24 --quality draft", &log), 0)
      << log;
  // exactly the last frame's picture and the record of what it was made from: no .pov, no log,
  // no partial image
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(run / "render"))
    names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"0002.png", "pictures.json"}));
}

// A picture made earlier from the same POV-Ray scene, size and quality is kept, not made again:
// an interrupted render goes on where it stopped. Another size, a picture gone or cut, or --again
// make it anew.
TEST_F(Render, APictureMadeFromTheSameInputIsKept) {
  const fs::path run = tiny_run(3);
  const std::string base = "render " + run.string() + " --frames all --quality draft ";
  std::string log;
  ASSERT_EQ(run_sandflow(base + "--width 32 --height 24", &log), 0) << log;
  EXPECT_EQ(log.find("kept"), std::string::npos) << log;
  const auto made_at = [&](int frame) {
    return fs::last_write_time(run / "render" / fmt::format("{:04d}.png", frame));
  };
  const auto first = made_at(1);
  ASSERT_EQ(run_sandflow(base + "--width 32 --height 24", &log), 0) << log;
  EXPECT_NE(log.find("render: 3 of 3 pictures kept, made earlier from the same scene, size and "
                     "quality (render/pictures.json; --again makes them anew)"),
            std::string::npos)
      << log;
  EXPECT_EQ(made_at(1), first);
  // every picture is still named on stdout, made or kept
  for (int frame = 1; frame <= 3; ++frame)
    EXPECT_NE(log.find(fmt::format("{:04d}.png", frame)), std::string::npos) << log;
  // one gone, one cut: those two are made again
  fs::remove(run / "render" / "0002.png");
  const std::string whole = read_text(run / "render" / "0003.png");
  std::ofstream(run / "render" / "0003.png", std::ios::binary | std::ios::trunc)
      << whole.substr(0, whole.size() - 1);
  ASSERT_EQ(run_sandflow(base + "--width 32 --height 24", &log), 0) << log;
  EXPECT_NE(log.find("render: 1 of 3 pictures kept"), std::string::npos) << log;
  EXPECT_EQ(sandflow::png_problem((run / "render" / "0003.png").string()), "");
  // another size, or --again: all made anew
  ASSERT_EQ(run_sandflow(base + "--width 32 --height 26", &log), 0) << log;
  EXPECT_EQ(log.find("kept"), std::string::npos) << log;
  ASSERT_EQ(run_sandflow(base + "--width 32 --height 26 --again", &log), 0) << log;
  EXPECT_EQ(log.find("kept"), std::string::npos) << log;
  // a record that is not one is warned of, and every picture made again
  std::ofstream(run / "render" / "pictures.json") << "[1, 2";
  ASSERT_EQ(run_sandflow(base + "--width 32 --height 26", &log), 0) << log;
  EXPECT_NE(log.find("pictures.json"), std::string::npos) << log;
  EXPECT_NE(log.find(": every picture is made again"), std::string::npos) << log;
  EXPECT_EQ(log.find("kept"), std::string::npos) << log;
}

// Without --scene the picture shows the scene the run ran: its run.json's text with its --set,
// even when the scene file has moved away (it said "pass it with --scene FILE") and whatever the
// file now says (a --set floor was drawn where the file put it).
TEST_F(Render, TheRunsOwnSceneIsDrawnFromItsRecord) {
  const auto scene = box.write("tiny.toml", kRenderScene);
  const auto out = box.dir / "run";
  std::string log;
  ASSERT_EQ(run_sandflow("run " + scene.string() +
                             " --mode dem --frames 1 --set 'geometry.0.point=[0, 0, "
                             "-0.0123]' --out " +
                             out.string(),
                         &log),
            0)
      << log;
  fs::remove(scene);
  ASSERT_EQ(
      run_sandflow("render " + out.string() + " --width 32 --height 24 --quality draft --keep-pov",
                   &log),
      0)
      << log;
  const std::string pov = sandflow_test::read_text(out / "render" / "0001.pov");
  EXPECT_NE(pov.find("-0.0123>"), std::string::npos) << pov.substr(0, 3000);
}

// A table1 folder is no run: render names its scenes' comparisons to render instead.
TEST_F(Render, ATable1FolderNamesItsScenes) {
  fs::create_directories(box.dir / "t1" / "bowl" / "surface" / "frames");
  box.write("t1/table1.csv", "scene,total\n");
  std::string log;
  EXPECT_EQ(run_sandflow("render " + (box.dir / "t1").string(), &log), 2) << log;
  EXPECT_NE(log.find("a table1 folder: render each scene's comparison on its own (" +
                     (box.dir / "t1" / "bowl").string() + ")"),
            std::string::npos)
      << log;
}

// POV-Ray splits its options at spaces and cannot open non-ASCII paths: a run folder whose path
// has both renders all the same; a look_at a hair from the location is still a direction.
TEST_F(Render, AFolderWithSpacesAndNonAsciiNamesRenders) {
  const auto scene = box.write("tiny.toml", kRenderScene);
  const fs::path run = box.dir / "run dir" / "sable fin \u00fc";
  std::string log;
  ASSERT_EQ(
      run_sandflow("run " + scene.string() + " --mode dem --frames 1 --out '" + run.string() + "'",
                   &log),
      0)
      << log;
  ASSERT_EQ(run_sandflow("render '" + run.string() +
                             "' --width 32 --height 24 --quality draft --keep-pov --set "
                             "'camera.position=[0.3,-0.3,1]' --set "
                             "'camera.look_at=[0.3,-0.3,0.9999999999]' --set 'camera.up=[0,1,0]'",
                         &log),
            0)
      << log;
  EXPECT_GT(read_rgb_png(run / "render" / "0001.png").width, 0);
  const std::string pov = read_text(run / "render" / "0001.pov");
  // (moved out along the view by |location| = 1.086 m: POV-Ray's own limit is about 1e-10 m)
  EXPECT_NE(pov.find("look_at <0.3,-0.3,-0.086278"), std::string::npos) << pov.substr(0, 600);
}

TEST_F(Render, BadFramesAreRefusedNamingTheOption) {
  const fs::path run = tiny_run(3);
  const std::string base = "render " + run.string() + " --width 32 --height 24 --quality draft ";
  struct Case {
    std::string frames, says;
  };
  const Case cases[] = {{"0", "frames count from 1"},     {"3:2", "comes before the first"},
                        {"4", "beyond the last frame"},   {"2:9", "beyond the last frame"},
                        {"abc", "is not a frame number"}, {"1:2:3", "expected N, A:B"},
                        {"1.5", "is not a frame number"}};
  for (const Case& c : cases) {
    std::string log;
    EXPECT_EQ(run_sandflow(base + "--frames " + c.frames, &log), 2) << c.frames << "\n" << log;
    EXPECT_NE(log.find("--frames " + c.frames + ":"), std::string::npos) << log;
    EXPECT_NE(log.find(c.says), std::string::npos) << log;
  }
  std::string log;
  EXPECT_EQ(run_sandflow(base + "--frames 2 --frame 2", &log), 2) << log;
  EXPECT_EQ(run_sandflow(base + "--quality best", &log), 2) << log;
  EXPECT_NE(log.find("--quality"), std::string::npos) << log;
  // nothing was rendered for a refused command
  EXPECT_FALSE(fs::exists(run / "render"));
}

TEST_F(Render, AFailedFrameIsNamedAndTheOthersAreKept) {
  const fs::path run = tiny_run(3);
  // a folder where frame 2's picture should go: its render cannot be put in place
  fs::create_directories(run / "render" / "0002.png" / "blocker");
  std::string log;
  EXPECT_EQ(run_sandflow("render " + run.string() +
                             " --frames all --width 32 --height 24 "
                             "--quality draft",
                         &log),
            4)
      << log;
  EXPECT_NE(log.find("1 of 3 frames failed to render (frame 2)"), std::string::npos) << log;
  EXPECT_NE(log.find("0002.png"), std::string::npos) << log;
  EXPECT_TRUE(fs::is_regular_file(run / "render" / "0001.png"));
  EXPECT_TRUE(fs::is_regular_file(run / "render" / "0003.png"));
}

// SIGTERM (or Ctrl-C) while rendering: the povray at work is ended, not left running to write
// into the folder after sandflow has gone (it was, with its .pov, log and partial picture), no
// other starts, and the pictures made stay, named.
TEST_F(Render, AStopSignalEndsThePovrayAtWorkAndKeepsThePicturesMade) {
  const fs::path run = tiny_run(12);  // (about 0.3 s a picture here: 3 s of work to stop)
  const fs::path log = box.dir / "render.log";
  const pid_t pid = sandflow_test::spawn(
      "render " + run.string() + " --frames all --width 640 --height 360 --jobs 1", log);
  while (!fs::exists(run / "render" / "0001.png") && waitpid(pid, nullptr, WNOHANG) == 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  kill(pid, SIGTERM);
  EXPECT_EQ(sandflow_test::wait_for(pid), 143) << read_text(log);
  EXPECT_NE(read_text(log).find("interrupted: "), std::string::npos) << read_text(log);
  EXPECT_NE(read_text(log).find(" pictures made (in place), frames 1"), std::string::npos)
      << read_text(log);
  // nothing but whole pictures, and nothing more comes
  const auto names = [&] {
    std::vector<std::string> v;
    for (const auto& e : fs::directory_iterator(run / "render"))
      v.push_back(e.path().filename().string());
    std::sort(v.begin(), v.end());
    return v;
  };
  const std::vector<std::string> at_exit = names();
  for (const std::string& name : at_exit)
    EXPECT_TRUE((name.size() == 8 && name.substr(4) == ".png") || name == "pictures.json") << name;
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  EXPECT_EQ(names(), at_exit);
  // the same command goes on from the pictures made
  const auto made = static_cast<int>(at_exit.size()) - 1;
  std::string again;
  ASSERT_EQ(
      run_sandflow("render " + run.string() + " --frames all --width 640 --height 360", &again), 0)
      << again;
  EXPECT_NE(again.find(fmt::format("render: {} of 12 pictures kept", made)), std::string::npos)
      << again;
}

// The programs a process started, by pid (from every thread's /proc/PID/task/TID/children).
std::vector<pid_t> children_of(pid_t pid) {
  std::vector<pid_t> out;
  std::error_code ec;
  for (const auto& task : fs::directory_iterator("/proc/" + std::to_string(pid) + "/task", ec)) {
    std::ifstream in(task.path() / "children");
    for (pid_t child = 0; in >> child;) out.push_back(child);
  }
  return out;
}

// Whether `pid` still runs (a zombie, killed and waiting to be reaped, does not).
bool still_running(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat;
  std::getline(in, stat);
  const std::size_t paren = stat.rfind(')');
  return paren != std::string::npos && paren + 2 < stat.size() && stat[paren + 2] != 'Z';
}

// The words that refuse a command the render `pid` stands in the way of, in `run`'s render/.
std::string held_by_render(const fs::path& run, pid_t pid) {
  return (run / "render").string() +
         ": the output folder is in use by another sandflow render (pid " + std::to_string(pid);
}

// The programs `pid` has started once it has started one (nothing if it ended first or after
// ten seconds).
std::vector<pid_t> first_children_of(pid_t pid) {
  std::vector<pid_t> children;
  for (int k = 0; k < 2000 && children.empty() && waitpid(pid, nullptr, WNOHANG) == 0; ++k) {
    children = children_of(pid);
    if (children.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return children;
}

// kill -9 (or a second Ctrl-C) ends sandflow at once, with no word: the povray at work must end
// with it, not render on into the folder with no one to clean up after it (it did).
TEST_F(Render, KilledWhileRenderingItLeavesNoPovrayRunning) {
  const fs::path run = tiny_run(12);
  const fs::path log = box.dir / "render.log";
  const pid_t pid = sandflow_test::spawn(
      "render " + run.string() + " --frames all --width 1920 --height 1080 --jobs 1", log);
  const std::vector<pid_t> povrays = first_children_of(pid);
  ASSERT_FALSE(povrays.empty()) << "no povray started: " << read_text(log);
  kill(pid, SIGKILL);
  EXPECT_EQ(sandflow_test::wait_for(pid), 128 + SIGKILL);
  for (const pid_t povray : povrays) {
    bool ended = false;
    // (it is killed at once; a picture at this size takes seconds)
    for (int k = 0; k < 50 && !ended; ++k) {
      ended = !still_running(povray);
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    EXPECT_TRUE(ended) << "povray " << povray << " runs on after sandflow was killed";
    if (!ended) kill(povray, SIGKILL);
  }
}

// Two renders of one run at once wrote the same scene, log and partial picture names and removed
// each other's: the second failed every frame with an empty log. The second is now refused, and
// the first finishes as if alone.
TEST_F(Render, ASecondRenderOfTheSameRunIsRefusedNotMixedIn) {
  const fs::path run = tiny_run(3);
  const fs::path log = box.dir / "first.log";
  const std::string args =
      "render " + run.string() + " --frames all --width 640 --height 360 --jobs 1";
  const pid_t first = sandflow_test::spawn(args, log);
  ASSERT_FALSE(first_children_of(first).empty()) << read_text(log);
  std::string second;
  EXPECT_EQ(run_sandflow(args, &second), 2) << second;
  EXPECT_NE(second.find(held_by_render(run, first)), std::string::npos) << second;
  EXPECT_EQ(sandflow_test::wait_for(first), 0) << read_text(log);
  for (int frame = 1; frame <= 3; ++frame)
    EXPECT_TRUE(fs::is_regular_file(run / "render" / fmt::format("{:04d}.png", frame))) << frame;
}

// A second report of a run whose report is rendering found each of its pictures refused by the
// render lock and wrote its page without them; it is now refused as a second render is, and the
// first's page shows every picture.
TEST_F(Render, ASecondReportOfTheSameRunIsRefusedWhileTheFirstRenders) {
  const fs::path run = tiny_run(12);
  fs::remove(run / "report.html");  // (the run's own page, without pictures)
  const fs::path log = box.dir / "first.log";
  const std::string args = "report " + run.string() + " --contact-sheet 12";
  const pid_t first = sandflow_test::spawn(args, log);
  ASSERT_FALSE(first_children_of(first).empty()) << read_text(log);
  std::string second;
  EXPECT_EQ(run_sandflow(args, &second), 2) << second;
  EXPECT_NE(second.find(held_by_render(run, first)), std::string::npos) << second;
  EXPECT_NE(second.find("wait for it to end or stop it, then report again"), std::string::npos)
      << second;
  EXPECT_EQ(sandflow_test::wait_for(first), 0) << read_text(log);
  for (int frame = 1; frame <= 12; ++frame)
    EXPECT_TRUE(fs::is_regular_file(run / "render" / fmt::format("{:04d}.png", frame))) << frame;
  // (the first's log says why a picture failed: once in CI, under the sanitizers, the first
  // rendered frames 1-4 and then wrote its page without the others, for a cause not yet found)
  const std::string page = read_text(run / "report.html");
  EXPECT_EQ(page.find("could not be rendered"), std::string::npos) << read_text(log);
}

// `run --force` on a run that a render is drawing removed render/ under it; now it waits its turn,
// and removes nothing.
TEST_F(Render, ARunForcedOverARunThatRendersIsRefused) {
  const fs::path run = tiny_run(3);
  const pid_t render = sandflow_test::spawn(
      "render " + run.string() + " --frames all --width 640 --height 360 --jobs 1",
      box.dir / "render.log");
  ASSERT_FALSE(first_children_of(render).empty()) << read_text(box.dir / "render.log");
  std::string log;
  EXPECT_EQ(run_sandflow("run " + (box.dir / "tiny.toml").string() +
                             " --mode dem --frames 3 --force --out " + run.string(),
                         &log),
            2)
      << log;
  EXPECT_NE(log.find(held_by_render(run, render)), std::string::npos) << log;
  EXPECT_TRUE(fs::exists(run / "summary.json"));  // (nothing removed)
  EXPECT_EQ(sandflow_test::wait_for(render), 0) << read_text(box.dir / "render.log");
  EXPECT_TRUE(fs::is_regular_file(run / "render" / "0003.png"));
}

// The report renders its contact sheet with render's machinery: a stop signal there stops the
// report too (each render's handler was installed anew, so the report rendered on past Ctrl-C).
TEST_F(Render, AStopSignalWhileTheReportRendersStopsTheReport) {
  const fs::path run = tiny_run(12);
  fs::remove(run / "report.html");  // (the run's own page, without pictures)
  const fs::path log = box.dir / "report.log";
  const pid_t pid = sandflow_test::spawn("report " + run.string() + " --contact-sheet 12", log);
  while (!fs::exists(run / "render" / "0001.png") && waitpid(pid, nullptr, WNOHANG) == 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  kill(pid, SIGINT);
  EXPECT_EQ(sandflow_test::wait_for(pid), 130) << read_text(log);
  const std::string text = read_text(log);
  EXPECT_NE(text.find("interrupted while rendering: the report is not written"), std::string::npos)
      << text;
  // said once, by the report: not also by the render it was in
  EXPECT_EQ(text.find("interrupted"), text.rfind("interrupted")) << text;
  EXPECT_FALSE(fs::exists(run / "report.html"));
  EXPECT_LT(std::distance(fs::directory_iterator(run / "render"), fs::directory_iterator{}), 12);
}

// A picture of the contact sheet cut short (a copy that stopped) is rendered again, not shown cut.
TEST_F(Render, AReportRendersAgainAPictureCutShort) {
  const fs::path run = tiny_run(2);
  std::string log;
  ASSERT_EQ(run_sandflow("report " + run.string() + " --contact-sheet 2", &log), 0) << log;
  const fs::path picture = run / "render" / "0002.png";
  const std::string whole = read_text(picture);
  ASSERT_GT(whole.size(), 100u);
  std::ofstream(picture, std::ios::binary | std::ios::trunc) << whole.substr(0, whole.size() / 2);
  ASSERT_NE(sandflow::png_problem(picture.string()), "");
  ASSERT_EQ(run_sandflow("report " + run.string() + " --contact-sheet 2", &log), 0) << log;
  EXPECT_NE(log.find("report: rendering " + run.string() + " frame 2 at 480x270"),
            std::string::npos)
      << log;
  EXPECT_EQ(log.find("frame 1 at"), std::string::npos) << log;  // (whole: not rendered again)
  EXPECT_EQ(sandflow::png_problem(picture.string()), "");
}

// A disk that fills while POV-Ray renders: POV-Ray's state file grows to about 20 bytes a pixel,
// POV-Ray stops with status 1 and its log (on the same disk) is cut short, saying nothing of the
// disk. The message says it, with what a picture needs; nothing half-made stays.
TEST_F(Render, AFullDiskIsSaidNotLeftToPovraysCutLog) {
  const fs::path small = box.dir / "small";
  const sandflow::test::SmallDisk disk(small, 2 << 20);
  if (!disk.mounted()) GTEST_SKIP() << disk.why_not();
  fs::copy(tiny_run(1), small / "run", fs::copy_options::recursive);
  // 700 kB left: room for the picture (about 45 kB) and its log, not for the state file (1.6 MB)
  ASSERT_TRUE(disk.fill_to(700'000));
  std::string log;
  EXPECT_EQ(run_sandflow("render " + (small / "run").string() + " --width 320 --height 240", &log),
            4)
      << log;
  EXPECT_NE(log.find("0001.png: cannot render: the disk holding " +
                     (small / "run" / "render").string() + " has "),
            std::string::npos)
      << log;
  EXPECT_NE(
      log.find(" kB free, and POV-Ray needs about 2.89 MB for a picture of 320 x 240 while it "
               "renders (its state file): make room, then render again"),
      std::string::npos)
      << log;
  for (const auto& e : fs::directory_iterator(small / "run" / "render"))
    EXPECT_EQ(e.path().string().find("partial"), std::string::npos) << e.path();
  // with room made, the same command renders the picture
  fs::remove(disk.filler());
  EXPECT_EQ(run_sandflow("render " + (small / "run").string() + " --width 320 --height 240", &log),
            0)
      << log;
  EXPECT_TRUE(fs::exists(small / "run" / "render" / "0001.png"));
}

// Under a memory limit (a control group of 150 MB, here), render runs no more POV-Rays at once
// than the memory left holds by the largest picture so far, says so, and its line says how many
// run; the kernel kills none, and every picture is made. (Large pictures: POV-Ray holds about
// 50 MB for one of 1600 x 1200, so four at once would not fit.)
TEST_F(Render, UnderAMemoryLimitFewerRunAtOnceAndNoneIsKilled) {
  sandflow::test::MemoryCgroup group("sandflow-test-" + std::to_string(::getpid()), 150'000'000);
  if (!group.ready()) GTEST_SKIP() << group.why_not();
  const fs::path run = tiny_run(4);
  std::string log;
  ASSERT_EQ(run_sandflow("render " + run.string() +
                             " --frames all --jobs 4 --width 1600 --height 1200 --quality draft",
                         &log, group.wrapper()),
            0)
      << log;
  const std::size_t said = log.find("render: a picture takes up to ");
  ASSERT_NE(said, std::string::npos) << log;
  const std::size_t colon = log.find(" were free: ", said);
  ASSERT_NE(colon, std::string::npos) << log;
  const int at_once = std::stoi(log.substr(colon + 12));
  EXPECT_LT(at_once, 4) << log;
  EXPECT_GE(at_once, 1) << log;
  EXPECT_NE(log.find(fmt::format("{} at once, not 4", at_once)), std::string::npos) << log;
  EXPECT_NE(log.find(fmt::format("draft, {} at once) frame 4/4", at_once)), std::string::npos)
      << log;
  EXPECT_EQ(group.oom_kills(), 0);
  for (const char* name : {"0001", "0002", "0003", "0004"})
    EXPECT_GT(sand_pixels(read_rgb_png(run / "render" / (std::string(name) + ".png"))), 50) << name;
}

TEST_F(Render, SceneCameraIsUsed) {
  std::string text = kRenderScene;
  text += "[camera]\nposition = [0.4, -0.5, 0.3]\nlook_at = [0, 0, 0.05]\nfov = 30\n";
  const fs::path run = tiny_run(1, text);
  std::string log;
  ASSERT_EQ(run_sandflow("render " + run.string() +
                             " --width 32 --height 24 --quality draft "
                             "--keep-pov",
                         &log),
            0)
      << log;
  const std::string pov = read_text(run / "render" / "0001.pov");
  EXPECT_NE(pov.find("location <0.4,-0.5,0.3>"), std::string::npos) << pov.substr(0, 600);
  EXPECT_NE(pov.find("look_at <0,0,0.05>"), std::string::npos);
  EXPECT_NE(pov.find("angle 30"), std::string::npos);
}

// --scene draws another scene file's geometry and camera: one that is not the scene the run ran
// (another name, other geometry, a solid moved) is warned of, the same scene moved, with a new
// camera or drawn otherwise is not.
TEST_F(Render, ASceneOtherThanTheRunsIsWarnedOf) {
  const fs::path run = tiny_run(1);
  std::string other = kRenderScene;
  other.replace(other.find("name = \"tiny\""), 13, "name = \"bin\"");
  other += "[[geometry]]\ntype = \"box\"\ncenter = [0.5, 0.0, 0.1]\nsize = [0.1, 0.1, 0.2]\n";
  const std::string base = "render " + run.string() + " --width 32 --height 24 --quality draft ";
  std::string log;
  ASSERT_EQ(run_sandflow(base + "--scene " + box.write("bin.toml", other).string(), &log), 0)
      << log;
  EXPECT_NE(log.find("is the scene 'bin' with 2 [[geometry]] tables; " + run.string() +
                     " ran 'tiny' with 1 [[geometry]] table (its run.json)"),
            std::string::npos)
      << log;
  const std::string camera =
      kRenderScene + "[camera]\nposition = [0.4, -0.5, 0.3]\nlook_at = [0, 0, 0.05]\n";
  ASSERT_EQ(run_sandflow(base + "--scene " + box.write("moved.toml", camera).string(), &log), 0)
      << log;
  EXPECT_EQ(log.find("warning"), std::string::npos) << log;
  // the same scene with its floor drawn as glass is the same solid; raised by a centimetre, not
  std::string glass = kRenderScene;
  glass.replace(glass.find("type = \"plane\""), 14, "type = \"plane\"\nrender = \"glass\"");
  ASSERT_EQ(run_sandflow(base + "--scene " + box.write("glass.toml", glass).string(), &log), 0)
      << log;
  EXPECT_EQ(log.find("warning"), std::string::npos) << log;
  std::string raised = kRenderScene;
  raised.replace(raised.find("type = \"plane\""), 14, "type = \"plane\"\npoint = [0, 0, 0.01]");
  const fs::path raised_file = box.write("raised.toml", raised);
  ASSERT_EQ(run_sandflow(base + "--scene " + raised_file.string(), &log), 0) << log;
  EXPECT_NE(log.find("warning: --scene " + raised_file.string() +
                     ": [[geometry]] table 0 ('geometry 0') is not the solid " + run.string() +
                     " ran (its run.json)"),
            std::string::npos)
      << log;
}

// The mesh drawn is the one the grains met (its record of the meshes it ran): its file edited since
// the run is warned of; the same mesh beside another scene file, under another name, is not.
TEST_F(Render, AMeshFileEditedSinceTheRunIsWarnedOf) {
  box.write("tet.stl", tetrahedron_stl(0.1));
  const std::string mesh =
      "[[geometry]]\ntype = \"mesh\"\nname = \"tet\"\nfile = \"tet.stl\"\n"
      "position = [0.3, 0.0, 0.0]\n";
  const fs::path run = tiny_run(1, kRenderScene + mesh);
  const std::string base = "render " + run.string() + " --width 32 --height 24 --quality draft";
  std::string log;
  ASSERT_EQ(run_sandflow(base, &log), 0) << log;
  EXPECT_EQ(log.find("warning"), std::string::npos) << log;
  // the same mesh elsewhere, named otherwise, drawn by --scene: the same solid
  fs::create_directories(box.dir / "elsewhere");
  box.write("elsewhere/copy.stl", tetrahedron_stl(0.1));
  std::string moved = kRenderScene + mesh;
  moved.replace(moved.find("tet.stl"), 7, "copy.stl");
  const fs::path moved_scene = box.write("elsewhere/tiny.toml", moved);
  ASSERT_EQ(run_sandflow(base + " --scene " + moved_scene.string(), &log), 0) << log;
  EXPECT_EQ(log.find("warning"), std::string::npos) << log;
  // the run's own mesh file edited: its apex 2 cm higher
  box.write("tet.stl", tetrahedron_stl(0.12));
  ASSERT_EQ(run_sandflow(base, &log), 0) << log;
  const std::string edited =
      "warning: [[geometry]] table 1 ('tet'): its mesh tet.stl is not the "
      "one " +
      run.string() + " ran (its record of the meshes it ran)";
  EXPECT_NE(log.find(edited), std::string::npos) << log;
  // a run without its summary.json (stopped, killed or still going): its run.json's record
  fs::remove(run / "summary.json");
  ASSERT_EQ(run_sandflow(base, &log), 0) << log;
  EXPECT_NE(log.find(edited), std::string::npos) << log;
  box.write("tet.stl", tetrahedron_stl(0.1));
  ASSERT_EQ(run_sandflow(base, &log), 0) << log;
  EXPECT_EQ(log.find("warning: [[geometry]]"), std::string::npos) << log;
}

TEST_F(Render, SetChangesTheLookOnly) {
  const fs::path run = tiny_run(1);
  std::string log;
  ASSERT_EQ(run_sandflow("render " + run.string() +
                             " --width 32 --height 24 --quality draft "
                             "--keep-pov --set camera.fov=25 --set geometry.0.render=hidden",
                         &log),
            0)
      << log;
  const std::string pov = read_text(run / "render" / "0001.pov");
  EXPECT_NE(pov.find("angle 25"), std::string::npos);
  EXPECT_EQ(pov.find("// geometry 0"), std::string::npos);  // the floor plane, hidden
  // what the grains met is not render's to change
  EXPECT_EQ(run_sandflow("render " + run.string() + " --set material.friction=1", &log), 2) << log;
  EXPECT_NE(log.find("--set material.friction=1: render takes only camera.KEY and "
                     "geometry.N.render"),
            std::string::npos)
      << log;
  EXPECT_EQ(run_sandflow("render " + run.string() + " --set geometry.0.point=[0,0,1]", &log), 2)
      << log;
  // and a bad look value is a scene error, named
  EXPECT_EQ(run_sandflow("render " + run.string() + " --set camera.fov=0", &log), 2) << log;
  EXPECT_NE(log.find("--set camera.fov: camera.fov = 0 is outside (0, 180)"), std::string::npos)
      << log;
}

TEST_F(Render, ComparisonFolderGetsOneCameraForBothRuns) {
  const auto scene = box.write("tiny.toml", kRenderScene);
  const auto out = box.dir / "cmp";
  std::string log;
  ASSERT_EQ(run_sandflow("compare " + scene.string() + " --frames 2 --out " + out.string(), &log),
            0)
      << log;
  // The two runs of so short a comparison are alike: lift the DEM run's grains, so that each
  // run alone would be framed differently.
  const std::string dem_last = (out / "dem" / "frames" / "0002.ply").string();
  sandflow::FrameData f = sandflow::read_ply(dem_last);
  for (auto& p : f.position) p.z += 0.2;
  sandflow::write_ply(dem_last, f);
  ASSERT_EQ(
      run_sandflow("render " + out.string() + " --width 32 --height 24 --quality draft --keep-pov",
                   &log),
      0)
      << log;
  const fs::path s = out / "surface" / "render", d = out / "dem" / "render";
  ASSERT_TRUE(fs::is_regular_file(s / "0002.png")) << log;
  ASSERT_TRUE(fs::is_regular_file(d / "0002.png")) << log;
  const std::string cs = camera_and_lights(read_text(s / "0002.pov"));
  ASSERT_FALSE(cs.empty());
  EXPECT_EQ(cs, camera_and_lights(read_text(d / "0002.pov")));
}

// --movie without --frames is a movie of every frame, not of the last alone (it was).
TEST_F(Render, AMovieAloneTakesEveryFrame) {
  if (sandflow::find_program("ffmpeg").empty())
    GTEST_SKIP() << "ffmpeg is not installed (sudo apt-get install ffmpeg)";
  const fs::path run = tiny_run(3);
  std::string log;
  ASSERT_EQ(run_sandflow(
                "render " + run.string() + " --width 32 --height 24 --quality draft --movie", &log),
            0)
      << log;
  for (int frame = 1; frame <= 3; ++frame)
    EXPECT_TRUE(fs::is_regular_file(run / "render" / fmt::format("{:04d}.png", frame))) << frame;
  EXPECT_EQ(sandflow::mp4_problem((run / "render" / "movie.mp4").string(), 3), "");
}

TEST_F(Render, MovieOfTheFrames) {
  if (sandflow::find_program("ffmpeg").empty())
    GTEST_SKIP() << "ffmpeg is not installed (sudo apt-get install ffmpeg)";
  const fs::path run = tiny_run(4);
  std::string log;
  // odd sizes: yuv420p needs even ones, the movie is padded
  ASSERT_EQ(run_sandflow("render " + run.string() +
                             " --frames 2:4 --width 33 --height 25 "
                             "--quality draft --movie",
                         &log),
            0)
      << log;
  const fs::path mp4 = run / "render" / "movie.mp4";
  ASSERT_TRUE(fs::is_regular_file(mp4)) << log;
  EXPECT_NE(log.find(mp4.string()), std::string::npos) << log;
  // an MP4: its first box is 'ftyp'
  const std::string head = read_text(mp4).substr(0, 8);
  EXPECT_EQ(head.substr(4, 4), "ftyp");
  // three frames at the run's 24 fps, H.264 in yuv420p
  if (!sandflow::find_program("ffprobe").empty()) {
    const fs::path probe = box.dir / "probe.txt";
    const std::string cmd =
        "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
        "stream=codec_name,pix_fmt,nb_read_frames,r_frame_rate -of "
        "default=nw=1 " +
        mp4.string() + " > " + probe.string() + " 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    const std::string info = read_text(probe);
    EXPECT_NE(info.find("codec_name=h264"), std::string::npos) << info;
    EXPECT_NE(info.find("pix_fmt=yuv420p"), std::string::npos) << info;
    EXPECT_NE(info.find("nb_read_frames=3"), std::string::npos) << info;
    EXPECT_NE(info.find("r_frame_rate=24/1"), std::string::npos) << info;
  }
}

TEST_F(Render, ComparisonMovieHasBothRunsSideBySide) {
  if (sandflow::find_program("ffmpeg").empty() || sandflow::find_program("ffprobe").empty())
    GTEST_SKIP() << "ffmpeg is not installed (sudo apt-get install ffmpeg)";
  const auto scene = box.write("tiny.toml", kRenderScene);
  const auto out = box.dir / "cmp";
  std::string log;
  ASSERT_EQ(run_sandflow("compare " + scene.string() + " --frames 1 --out " + out.string(), &log),
            0)
      << log;
  ASSERT_EQ(run_sandflow("render " + out.string() +
                             " --frames all --width 32 --height 24 --quality draft --movie",
                         &log),
            0)
      << log;
  EXPECT_TRUE(fs::is_regular_file(out / "surface" / "render" / "movie.mp4")) << log;
  EXPECT_TRUE(fs::is_regular_file(out / "dem" / "render" / "movie.mp4")) << log;
  const fs::path both = out / "render" / "side_by_side.mp4";
  ASSERT_TRUE(fs::is_regular_file(both)) << log;
  // two 32-pixel pictures side by side
  const fs::path probe = box.dir / "probe.txt";
  const std::string cmd =
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
      "stream=width,height,nb_read_frames -of default=nw=1 " +
      both.string() + " > " + probe.string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const std::string info = read_text(probe);
  EXPECT_NE(info.find("width=64"), std::string::npos) << info;
  EXPECT_NE(info.find("height=24"), std::string::npos) << info;
  EXPECT_NE(info.find("nb_read_frames=1"), std::string::npos) << info;
}

TEST_F(Render, WithoutFfmpegTheFramesAreRenderedAndTheMessageSaysHowToInstallIt) {
  const fs::path run = tiny_run(2);
  // a PATH with povray and the shell's tools but no ffmpeg
  const fs::path bin = box.dir / "bin";
  fs::create_directories(bin);
  fs::create_symlink(sandflow::find_povray(), bin / "povray");
  std::string log;
  const std::string cmd =
      "render " + run.string() + " --frames all --width 32 --height 24 --quality draft --movie";
  const char* path_env = std::getenv("PATH");
  const std::string saved = path_env ? path_env : "";
  ::setenv("PATH", bin.c_str(), 1);
  const int rc = run_sandflow(cmd, &log);
  ::setenv("PATH", saved.c_str(), 1);
  EXPECT_EQ(rc, 2) << log;
  EXPECT_NE(log.find("sudo apt-get install ffmpeg"), std::string::npos) << log;
  EXPECT_TRUE(fs::is_regular_file(run / "render" / "0001.png")) << log;
  EXPECT_TRUE(fs::is_regular_file(run / "render" / "0002.png")) << log;
  EXPECT_FALSE(fs::exists(run / "render" / "movie.mp4"));
}

}  // namespace

// Hostile inputs past the parser: each gives its documented exit status and a message that names
// the file and the key, within `timeout 30`, never a crash, a hang or a silently wrong run.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "cli_runner.hpp"
#include "core/error.hpp"
#include "io/folder_lock.hpp"
#include "sim/world.hpp"
#include "support/sanitizers.hpp"

namespace fs = std::filesystem;

namespace {

using sandflow_test::run_sandflow;
using sandflow_test::Sandbox;

// A scene with the tiny block and one mesh entry (its keys after `file`).
std::string mesh_scene(const std::string& file, const std::string& keys = "") {
  return sandflow_test::tiny_block_scene(20) + "[[geometry]]\ntype = \"mesh\"\nfile = \"" + file +
         "\"\n" + keys + "\n";
}

// `sandflow ARGS`, bounded by `timeout 30` (124 when it ran out).
int bounded(const std::string& args, std::string* log) {
  return sandflow_test::run_sandflow(args, log, "timeout 30");
}

// the log has "FILE:LINE:COL: WHAT" for some line and column (std::regex would do, but GCC 12
// warns inside it under the sanitizers, and the warnings are errors)
bool has_placed(const std::string& log, const std::string& file, const std::string& what) {
  for (std::size_t at = log.find(file + ":"); at != std::string::npos;
       at = log.find(file + ":", at + 1)) {
    std::size_t k = at + file.size();
    bool ok = true;
    for (int part = 0; part < 2 && ok; ++part) {  // ":LINE" then ":COL"
      ok = k < log.size() && log[k] == ':';
      std::size_t digits = 0;
      for (++k; ok && k < log.size() && std::isdigit(static_cast<unsigned char>(log[k])); ++k)
        ++digits;
      ok = ok && digits > 0;
    }
    if (ok && log.compare(k, 2 + what.size(), ": " + what) == 0) return true;
  }
  return false;
}

bool has(const std::string& log, const std::string& part) {
  return log.find(part) != std::string::npos;
}

// A finished run of one frame of the tiny block in box.dir/out (empty when it failed: see log).
fs::path one_frame_run(const Sandbox& box, std::string* log) {
  const fs::path scene = box.write("tiny.toml", sandflow_test::tiny_block_scene(20));
  const fs::path out = box.dir / "out";
  const int status =
      bounded("run " + scene.string() + " --frames 1 --export none --out " + out.string(), log);
  return status == 0 ? out : fs::path();
}

TEST(HostileInputs, AMeshOfHugeCoordinatesIsRefusedBeforeTheWorldIsBuilt) {
  Sandbox box;
  box.write("huge.obj", "v 1e308 1e308 1e308\nv -1e308 -1e308 -1e308\nv 1e308 -1e308 0\nf 1 2 3\n");
  box.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  std::string log;
  // coordinates whose extent overflows: the file and the entry are named
  const auto huge = box.write("huge.toml", mesh_scene("huge.obj"));
  EXPECT_EQ(bounded("run " + huge.string() + " --check", &log), 2) << log;
  EXPECT_TRUE(has(log, "huge.obj") && has(log, "geometry 1") && has(log, "too large")) << log;
  // a sane mesh scaled or sized out of reach: the keys are named, no particle count is made
  for (const std::string keys : {"scale = 1e307", "size = 1e300", "scale = 1e30"}) {
    const auto scene = box.write("far.toml", mesh_scene("tri.obj", keys));
    EXPECT_EQ(bounded("run " + scene.string() + " --check", &log), 2) << keys << "\n" << log;
    EXPECT_TRUE(has(log, "far.toml: geometry 1") && has(log, "scale, size and position")) << log;
  }
  // large but within reach: refused for its particle count, which is given as a number
  const auto large = box.write("large.toml", mesh_scene("tri.obj", "size = 1e6"));
  EXPECT_EQ(bounded("run " + large.string() + " --check", &log), 2) << log;
  EXPECT_TRUE(has(log, "large.toml: geometry 1: sampling the mesh") &&
              has(log, "e+") && !has(log, "about 0 boundary"))
      << log;
}

// Each heightmap, pour and mesh within its own limit, but so many that the scene would hold many
// times the largest one: the limits hold for the scene's entries together (docs/fuzzing.md).
TEST(HostileInputs, ManyEntriesEachWithinItsLimitAreRefusedTogether) {
  Sandbox box;
  std::string log;
  // 17 noise terrains of 1024 x 1024 samples: one more than the samples of a 4096 x 4096 one
  std::string terrains = sandflow_test::tiny_block_scene(20);
  for (int k = 0; k < 17; ++k)
    terrains += fmt::format(
        "[[geometry]]\ntype = \"heightmap\"\nextent = [{}, 0, {}, 2]\nnoise = {{ wavelength = "
        "0.001 }}\n",
        10 * k, 10 * k + 2);
  const auto maps = box.write("maps.toml", terrains);
  EXPECT_EQ(bounded("run " + maps.string() + " --check", &log), 2) << log;
  EXPECT_TRUE(has(log, "maps.toml:") &&
              has(log, "geometry[17].noise brings the scene's heightmaps") && has(log, "16777216"))
      << log;
  // 65 planes: the 65th is refused (every grain and every height-field column asks each one)
  std::string planes = sandflow_test::tiny_block_scene(20);
  for (int k = 0; k < 64; ++k)
    planes += fmt::format("[[geometry]]\ntype = \"plane\"\npoint = [0, 0, {}]\n", -k);
  const auto many = box.write("planes.toml", planes);
  EXPECT_EQ(bounded("run " + many.string() + " --check", &log), 2) << log;
  EXPECT_TRUE(has(log, "planes.toml:") &&
              has(log, "geometry[64]: the scene has 65 [[geometry]] entries"))
      << log;
  // two pours of 10 million slots each
  const std::string pour =
      "[[emitter]]\ntype = \"pour\"\nshape = \"rect\"\ncount = 10\ncenter = [0, 0, 1]\n"
      "size = [30.0, 30.0, 0.1]\n";
  const auto pours = box.write("pours.toml", sandflow_test::tiny_block_scene(20) + pour + pour);
  EXPECT_EQ(bounded("run " + pours.string() + " --check --mode dem", &log), 2) << log;
  EXPECT_TRUE(has(log, "pours.toml:") && has(log, "emitter[2].size brings the scene's pours") &&
              has(log, "16777216"))
      << log;
  // two flat squares of 6 m, each sampled at 0.0025 m into about 11.8 million points before merging
  box.write("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
  const std::string quad = "[[geometry]]\ntype = \"mesh\"\nfile = \"quad.obj\"\nsize = 6.0\n";
  const auto quads = box.write("quads.toml", sandflow_test::tiny_block_scene(20) + quad + quad);
  EXPECT_EQ(bounded("run " + quads.string() + " --check", &log), 2) << log;
  EXPECT_TRUE(has(log, "quads.toml: geometry 2: sampling the mesh") &&
              has(log, "left of the limit of 20000000 for all of the scene's meshes"))
      << log;
}

TEST(HostileInputs, ARunTooLongForItsFrameCountIsRefusedNamingTheKeys) {
  Sandbox box;
  std::string log;
  const std::string tiny = sandflow_test::tiny_block_scene(20);
  ASSERT_TRUE(has(tiny, "[output]"));
  auto with_output_key = [&](const std::string& key) {
    std::string text = tiny;
    return text.replace(text.find("[output]"), 8, "[output]\n" + key);
  };
  const auto duration = box.write("duration.toml", with_output_key("duration = 7.2e7"));
  EXPECT_EQ(bounded("run " + duration.string() + " --check", &log), 2) << log;
  EXPECT_TRUE(has(log, "output.duration") && has(log, "more than the limit")) << log;
  const auto s = box.write("settle.toml", with_output_key("settle_time = 1e300"));
  EXPECT_EQ(bounded("run " + s.string() + " --check", &log), 2) << log;
  EXPECT_TRUE(has(log, "output.settle_time") && has(log, "more than the limit")) << log;
}

TEST(HostileInputs, AKeyWithAControlCharacterIsShownWhole) {
  Sandbox box;
  std::string log;
  std::string text = sandflow_test::tiny_block_scene(20);
  text.replace(text.find("[material]"), 10, "[material]\n\"a\\u0000b\\u001bc\" = 1");
  const auto scene = box.write("nul.toml", text);
  EXPECT_EQ(bounded("run " + scene.string() + " --check", &log), 2) << log;
  EXPECT_TRUE(has(log, "material.a\\u0000b\\u001bc is not a key of")) << log;
}

// Each number in its range, their product not: the loader's own checks (a block too small for
// its grains) catch most such scenes; what passes them meets the time step's check.
TEST(HostileInputs, MaterialNumbersWhoseProductsOverflowAreRefused) {
  for (const auto& [density, diameter] : {std::pair{1e300, 1e10}, std::pair{2600.0, 1e300}}) {
    sandflow::SceneConfig s;
    s.path = "overflow.toml";
    s.material.density = density;
    s.material.diameter = diameter;
    try {
      sandflow::choose_time_step(s);
      ADD_FAILURE() << "no error for density " << density << ", diameter " << diameter;
    } catch (const sandflow::InputError& e) {
      EXPECT_TRUE(has(e.what(), "overflow.toml: material.density") &&
                  has(e.what(), "not finite positive numbers"))
          << e.what();
    }
  }
}

// Numbers each finite and in range, but contacts too soft for the grains' weight: the heaviest
// grain would sink past the overlap guard as soon as it lands, so --check refuses the scene. The
// error is placed at k_n, as the loader places its own: the --set that gave it, else its line.
TEST(HostileInputs, ContactsTooSoftForTheGrainsWeightAreRefusedByCheck) {
  Sandbox box;
  const fs::path scene = box.dir / "soft.toml";
  std::ofstream(scene) << sandflow_test::tiny_block_scene(20);
  for (const std::string set : {"material.k_n=1e-300", "material.density=1e300"}) {
    std::string log;
    EXPECT_EQ(bounded("run " + scene.string() + " --check --set " + set, &log), 2) << set;
    EXPECT_TRUE((set.rfind("material.k_n", 0) == 0
                     ? has(log, "--set material.k_n: material.density")
                     : has_placed(log, "soft.toml", "material.density")) &&
                has(log, "would sink") && has(log, "max_overlap_stop"))
        << log;
  }
  // k_n of 1e4 N/m holds a 1 cm grain of sand (it sinks 1.3e-6 m, 0.013 % of its diameter)
  std::string log;
  EXPECT_EQ(bounded("run " + scene.string() + " --check", &log), 0) << log;
}

// A checkpoint of a terabyte (a sparse file: it takes no disk) is refused by its size, before
// anything is read or allocated for it.
TEST(HostileInputs, ACheckpointLargerThanHalfTheMemoryIsRefusedUnread) {
  Sandbox box;
  std::string log;
  const fs::path out = one_frame_run(box, &log);
  ASSERT_FALSE(out.empty()) << log;
  fs::remove(out / "summary.json");  // (a finished run is not resumed)
  fs::resize_file(out / "checkpoint.bin", std::uintmax_t{1} << 40);
  EXPECT_EQ(bounded("run --resume " + out.string(), &log), 2) << log;
  EXPECT_TRUE(has(log,
                  "checkpoint.bin: the checkpoint is 1099511627776 bytes, more than half of "
                  "this machine's memory"))
      << log;
}

// Grains that end inside a mesh (here put there by a block inside a closed cube: they touch none
// of its particles, so the overlap guard has nothing to see) make the run exit 3, its results
// written.
TEST(HostileInputs, GrainsEndingInsideTheGeometryMakeTheRunFail) {
  Sandbox box;
  box.write("cube.obj",
            "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv -1 -1 2\nv 1 -1 2\nv 1 1 2\nv -1 1 2\n"
            "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\n"
            "f 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n");
  const fs::path scene = box.write(
      "inside.toml", sandflow_test::tiny_block_scene(20, 30, 0.5) +
                         "[[geometry]]\ntype = \"mesh\"\nfile = \"cube.obj\"\nscale = 0.5\n");
  const fs::path out = box.dir / "out";
  std::string log;
  EXPECT_EQ(bounded("run " + scene.string() + " --mode dem --frames 1 --export none --out " +
                        out.string(),
                    &log),
            3)
      << log;
  EXPECT_TRUE(has(log, "inside.toml: 20 grains ended inside the geometry")) << log;
  EXPECT_TRUE(fs::exists(out / "summary.json") && fs::exists(out / "final_grains.ply"));
}

TEST(HostileInputs, SpecialFilesAreRefusedByTheirType) {
  Sandbox box;
  std::string log;
  EXPECT_EQ(bounded("run /dev/zero --check", &log), 2) << log;
  EXPECT_TRUE(has(log, "/dev/zero: the scene file is a character device, not a file")) << log;
  const fs::path fifo = box.dir / "scene.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(bounded("run " + fifo.string() + " --check", &log), 2) << log;
  EXPECT_TRUE(has(log, "is a FIFO, not a file")) << log;
  const auto mesh = box.write("zero.toml", mesh_scene("/dev/zero"));
  EXPECT_EQ(bounded("run " + mesh.string() + " --check", &log), 2) << log;
  EXPECT_TRUE(has(log, "the mesh file '/dev/zero' is a character device, not a file")) << log;
}

TEST(HostileInputs, AFolderHeldByAnotherRunIsRefusedNamingTheHolder) {
  Sandbox box;
  std::string log;
  const auto scene = box.write("tiny.toml", sandflow_test::tiny_block_scene(20));
  const fs::path out = box.dir / "out";
  {
    const sandflow::FolderLock held(out.string());
    EXPECT_EQ(bounded("run " + scene.string() + " --mode dem --frames 2 --force --out " + out.string(), &log), 2)
        << log;
    EXPECT_TRUE(has(log, "in use by another sandflow run (pid " + std::to_string(::getpid())))
        << log;
    EXPECT_FALSE(fs::exists(out / "run.json"));  // nothing touched
    EXPECT_EQ(bounded("run --resume " + out.string(), &log), 2) << log;
    EXPECT_EQ(bounded("compare " + scene.string() + " --frames 2 --seeds 1 --out " + out.string(), &log), 2)
        << log;
    EXPECT_TRUE(has(log, "in use")) << log;
  }
  // released with its holder: the run goes
  EXPECT_EQ(bounded("run " + scene.string() + " --mode dem --frames 2 --force --out " + out.string(), &log), 0)
      << log;
}

// The lock refuses an output path that is a file, for every command that writes a folder, and
// leaves the file as it was.
TEST(HostileInputs, AnOutputPathThatIsAFileIsRefused) {
  Sandbox box;
  std::string log;
  const auto scene = box.write("tiny.toml", sandflow_test::tiny_block_scene(20));
  const auto file = box.write("taken", "not a folder\n");
  for (const std::string& cmd : {"run " + scene.string() + " --mode dem --frames 2 --force --out ",
                                "compare " + scene.string() + " --frames 2 --seeds 1 --out ",
                                std::string("table1 --scale 0.0001 --frames 1 --scenes floor --out ")}) {
    EXPECT_EQ(bounded(cmd + file.string(), &log), 2) << cmd << "\n" << log;
    EXPECT_TRUE(has(log, "taken: the output path exists and is not a folder")) << cmd << "\n" << log;
  }
  EXPECT_EQ(sandflow_test::read_text(file), "not a folder\n");
}

// Two real runs into one folder: the second (with --force) is refused while the first goes on,
// and the first ends with every row and frame it owes.
TEST(HostileInputs, ASecondRunIntoARunningOnesFolderIsRefused) {
  Sandbox box;
  std::string log;
  const auto scene = box.write("tiny.toml", sandflow_test::tiny_block_scene(400));
  const fs::path out = box.dir / "out";
  const fs::path first_log = box.dir / "first.log";
  const int frames = 60;
  const std::string first = std::string(SANDFLOW_BINARY) + " run " + scene.string() +
                            " --mode dem --frames " + std::to_string(frames) + " --out " +
                            out.string() + " > " + first_log.string() + " 2>&1";
  std::thread runner([&] { std::system(first.c_str()); });
  // wait until the first run is under way (its run.json written), at most 20 s
  for (int k = 0; k < 200 && !fs::exists(out / "run.json"); ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const bool started = fs::exists(out / "run.json");
  const int second = bounded(
      "run " + scene.string() + " --mode dem --frames 2 --force --out " + out.string(), &log);
  const bool still_running = !fs::exists(out / "summary.json");
  runner.join();
  ASSERT_TRUE(started) << sandflow_test::read_text(first_log);
  if (!still_running) GTEST_SKIP() << "the first run ended before the second started";
  EXPECT_EQ(second, 2) << log;
  EXPECT_TRUE(has(log, "in use by another sandflow run")) << log;
  std::ifstream csv(out / "stats.csv");
  std::string line;
  int rows = -1;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, frames) << sandflow_test::read_text(first_log);
  EXPECT_TRUE(fs::exists(out / "summary.json"));
}

// An emitter that places grains deep in a solid (a block half under the floor, a floor raised
// above the block) is refused with exit 2, naming the emitter and the solid, not stopped by the
// overlap guard with advice about k_n. The same block above the floor runs.
TEST(HostileInputs, AnEmitterPlacingGrainsInsideASolidIsRefusedNamingBoth) {
  Sandbox box;
  const fs::path scene = box.write("buried.toml", sandflow_test::tiny_block_scene(20));
  for (const std::string set :
       {"emitter.0.center=[0,0,0]", "geometry.0.point=[0,0,0.2]", "geometry.0.normal=[0,0,-1]"}) {
    std::string log;
    EXPECT_EQ(bounded("run " + scene.string() + " --frames 1 --export none --set '" + set +
                          "' --out " + (box.dir / "out").string() + " --force",
                      &log),
              2)
        << set << "\n"
        << log;
    EXPECT_TRUE(has_placed(log, "buried.toml", "emitter[0] places a grain at") &&
                has(log, "inside geometry[0]") && has(log, "move the emitter or the solid") &&
                !has(log, "raise k_n"))
        << set << "\n"
        << log;
  }
  std::string log;
  EXPECT_EQ(bounded("run " + scene.string() + " --frames 1 --export none --out " +
                        (box.dir / "out").string() + " --force",
                    &log),
            0)
      << log;
}

// A restitution near 0 needs a dashpot so strong that the step of an ordinary scene would let it
// overshoot and blow up at the first contact: the derived step shrinks for it (the run ends with
// its overlaps small), a fixed step above the bound is refused naming the restitution, and a
// restitution below the law's least is refused by the loader.
TEST(HostileInputs, AStrongDashpotShortensTheStepOrIsRefused) {
  Sandbox box;
  const fs::path scene = box.write("damped.toml", sandflow_test::tiny_block_scene(20));
  const fs::path out = box.dir / "out";
  std::string log;
  ASSERT_EQ(bounded("run " + scene.string() +
                        " --frames 2 --export none --set "
                        "material.restitution=1e-4 --out " +
                        out.string(),
                    &log),
            0)
      << log;
  const sandflow::TimeStep plain = [] {
    sandflow::SceneConfig s;
    s.material.k_n = 1e4;
    return sandflow::choose_time_step(s);
  }();
  sandflow::SceneConfig damped;
  damped.material.k_n = 1e4;
  damped.material.restitution = 1e-4;
  const sandflow::TimeStep strong = sandflow::choose_time_step(damped);
  // the bound t_c / (3 pi beta), beta near its largest (50): about t_c / 470, against t_c / 20
  // (dt is a frame over a whole number of steps: at most the bound, within a step's share of it)
  const double bound = strong.t_c / (3 * sandflow::kPi * sandflow::damping_beta(1e-4));
  EXPECT_LE(strong.dt, bound);
  EXPECT_GT(strong.dt, bound * (1 - 1.0 / strong.substeps));
  EXPECT_LE(plain.dt, 0.05 * plain.t_c);  // e = 0.3: the step is the usual one
  EXPECT_GT(plain.dt, 0.05 * plain.t_c * (1 - 1.0 / plain.substeps));

  EXPECT_EQ(bounded("run " + scene.string() +
                        " --check --set material.restitution=1e-4 --set "
                        "simulation.dt=1e-5",
                    &log),
            2)
      << log;
  EXPECT_TRUE(has(log, "--set simulation.dt: simulation.dt = 1e-05 s is above the stable bound") &&
              has(log, "material.restitution = 0.0001"))
      << log;
  EXPECT_EQ(bounded("run " + scene.string() + " --check --set material.restitution=1e-9", &log), 2)
      << log;
  EXPECT_TRUE(has(log, "material.restitution = 1e-09 is below")) << log;
}

// A run record whose counts are not whole numbers in range (edited: a float, 1e20) is refused
// naming the field, before any of it is converted.
TEST(HostileInputs, ARunRecordWithCountsOutOfRangeIsRefused) {
  Sandbox box;
  std::string log;
  const fs::path out = one_frame_run(box, &log);
  ASSERT_FALSE(out.empty()) << log;
  const std::string record = sandflow_test::read_text(out / "run.json");
  const std::size_t at = record.find("\"frames\": 1");
  ASSERT_NE(at, std::string::npos) << record;
  for (const std::string value : {"1e20", "2.5", "-3"}) {
    std::string edited = record;
    edited.replace(at, std::string("\"frames\": 1").size(), "\"frames\": " + value);
    std::ofstream(out / "run.json") << edited;
    EXPECT_EQ(bounded("run --resume " + out.string(), &log), 2) << value << "\n" << log;
    EXPECT_TRUE(has(log, "run.json: frames ") && has(log, "is not a whole number from 0 to"))
        << value << "\n"
        << log;
  }
}

// A VDB voxel finer than d / 200 is refused at load: OpenVDB drops a sphere wider than 100 voxels
// from the level set, which left it empty with exit 0. Frame counts out of range say the range,
// counts that are not whole numbers say so, calibrate's rig numbers are numbers in range, words a
// command does not take are named with it, and an empty --out is refused.
TEST(HostileInputs, AVdbVoxelTooFineAndFrameCountsOutOfRangeAreRefused) {
  Sandbox box;
  const fs::path scene = box.write("fine.toml", sandflow_test::tiny_block_scene(20));
  std::string log;
  EXPECT_EQ(bounded("run " + scene.string() + " --check --set output.vdb_voxel_size=2e-5", &log), 2)
      << log;
  EXPECT_TRUE(has(log, "output.vdb_voxel_size = 2e-05 m is below 5e-05 m")) << log;
  EXPECT_EQ(bounded("run " + scene.string() + " --check --set output.vdb_voxel_size=5e-5", &log), 0)
      << log;
  for (const std::string frames : {"0", "20000000"}) {
    EXPECT_EQ(bounded("run " + scene.string() + " --check --frames " + frames, &log), 2) << log;
    EXPECT_TRUE(has(log, "--frames: " + frames + " is not in range 1 to 10000000")) << log;
  }
  // a count written as a decimal or with an exponent is not a whole number: CLI11's range check
  // alone called it out of range
  for (const std::string option : {"--grains 2e2", "--threads 1.0", "--frames 1x"}) {
    EXPECT_EQ(bounded("run " + scene.string() + " --check " + option, &log), 2) << log;
    EXPECT_TRUE(has(log, option.substr(0, option.find(' ')) + ": " +
                             option.substr(option.find(' ') + 1) + " is not a whole number"))
        << log;
  }
  EXPECT_EQ(bounded("run " + scene.string() + " --check --grains 99999999999999999999", &log), 2)
      << log;
  EXPECT_TRUE(has(log, "is not in range 1 to 2000000000")) << log;
  // calibrate's rig numbers: nan and inf are out of range (CLI11's Range let nan through, and a
  // calibration on a base of nan grains began), a word is no number (Range called it out of range)
  for (const auto& [option, message] : std::vector<std::pair<std::string, std::string>>{
           {"--base nan", "--base: nan is not in range 4 to 40"},
           {"--base inf", "--base: inf is not in range 4 to 40"},
           {"--base 3.9", "--base: 3.9 is not in range 4 to 40"},
           {"--base ten", "--base: ten is not a number"},
           {"--tilt-rate nan", "--tilt-rate: nan is not in range 0.1 to 30"},
           {"--tilt-rate 2x", "--tilt-rate: 2x is not a number"}}) {
    EXPECT_EQ(bounded("calibrate " + scene.string() + " " + option, &log), 2) << option << log;
    EXPECT_TRUE(has(log, message)) << log;
  }
  // an option given twice is named so, not "At Most 1 required" (which reads like a missing value)
  EXPECT_EQ(bounded("run " + scene.string() + " --check --grains 5 --grains 6", &log), 2) << log;
  EXPECT_TRUE(has(log, "--grains is given 2 times: give it once")) << log;
  // words a command does not take are named in order, with the command (CLI11: "The following
  // arguments were not expected: dem --mode")
  EXPECT_EQ(bounded("compare " + scene.string() + " --mode dem", &log), 2) << log;
  EXPECT_TRUE(has(log, "`sandflow compare` takes no option --mode (given: --mode dem)")) << log;
  EXPECT_TRUE(has(log, "Run sandflow compare --help for what it takes.")) << log;
  EXPECT_EQ(bounded("frobnicate", &log), 2) << log;
  EXPECT_TRUE(has(log, "frobnicate: sandflow has no such command; its commands: run,")) << log;
  // CLI11's other words, said with the command and what was meant: no command ("A subcommand is
  // required"), an option before it, a missing argument ("dir is required"), an option without
  // its value ("1 required INT:INT in [1 - 100] missing"); each says where to read more
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {"", "sandflow: give a command; its commands: run,"},
           {"--fast run",
            "sandflow takes no option --fast before its command; options go after it"},
           {"render", "`sandflow render` needs its DIR: run folder"},
           {"calibrate",
            "`sandflow calibrate` needs its SCENE: scene file (TOML)\nRun sandflow "
            "calibrate --help for what it takes."},
           {"compare " + scene.string() + " --seeds",
            "--seeds needs a value (INT:INT in [1 - 100])\nRun sandflow compare --help"}}) {
    EXPECT_EQ(bounded(args, &log), 2) << args << log;
    EXPECT_TRUE(has(log, message)) << args << log;
  }
  // an empty output folder is not the default one
  EXPECT_EQ(bounded("run " + scene.string() + " --frames 1 --out ''", &log), 2) << log;
  EXPECT_TRUE(has(log, "--out: an empty folder name")) << log;
}

// An angle of repose given in radians is in range as degrees: the run goes on, and says so.
TEST(HostileInputs, AnAngleThatReadsLikeRadiansIsWarnedOf) {
  Sandbox box;
  const fs::path scene = box.write("radians.toml", sandflow_test::tiny_block_scene(20));
  std::string log;
  EXPECT_EQ(bounded("run " + scene.string() + " --check --set surface.repose_angle=0.6", &log), 0)
      << log;
  EXPECT_TRUE(has(log,
                  "warning: --set surface.repose_angle: surface.repose_angle = 0.6 is in "
                  "degrees, a heap all but flat; if it was meant in radians, write 34.38"))
      << log;
}

// The files of a run folder are read only when they are files: a FIFO would block the reader for
// ever, /dev/zero behind a link would fill the memory (report grew 0.75 GB a second), a folder
// gave rc 1 with libstdc++'s words. A checkpoint that is a link to nothing (storage not mounted)
// is not "no checkpoint yet", which ran the run again from the start over it, and a record whose
// scene_file is "" is refused before the run, not with rc 1 after it.
TEST(HostileInputs, RunFolderFilesThatAreNoFilesAreRefusedNotWaitedOn) {
  Sandbox box;
  std::string log;
  const fs::path out = one_frame_run(box, &log);
  ASSERT_FALSE(out.empty()) << log;
  const fs::path c = box.dir / "copy";
  const auto fresh = [&] {
    fs::remove_all(c);
    fs::copy(out, c, fs::copy_options::recursive);
  };
  fresh();
  fs::remove(c / "summary.json");
  ASSERT_EQ(mkfifo((c / "summary.json").c_str(), 0600), 0);
  EXPECT_EQ(bounded("report " + c.string() + " --no-render", &log), 2) << log;
  EXPECT_TRUE(has(log, "summary.json: the JSON file is a FIFO, not a file")) << log;
  EXPECT_EQ(bounded("run --resume " + c.string(), &log), 2) << log;
  EXPECT_TRUE(has(log, "summary.json: the summary is a FIFO, not a file")) << log;

  fresh();
  fs::remove(c / "stats.csv");
  fs::create_symlink("/dev/zero", c / "stats.csv");
  EXPECT_EQ(bounded("report " + c.string() + " --no-render", &log), 2) << log;
  EXPECT_TRUE(has(log, "stats.csv: the statistics file is a character device, not a file")) << log;

  fresh();
  fs::remove(c / "run.json");
  fs::create_directory(c / "run.json");
  EXPECT_EQ(bounded("run --resume " + c.string(), &log), 2) << log;
  EXPECT_TRUE(has(log, "run.json: the run record is a folder, not a file")) << log;

  fresh();
  fs::remove(c / "summary.json");  // (unfinished: a resume reads the checkpoint)
  fs::remove(c / "checkpoint.bin");
  fs::create_symlink("/nonexistent/sandflow-checkpoint", c / "checkpoint.bin");
  EXPECT_EQ(bounded("run --resume " + c.string(), &log), 2) << log;
  EXPECT_TRUE(has(log,
                  "checkpoint.bin: the checkpoint is a link to nothing "
                  "(/nonexistent/sandflow-checkpoint)"))
      << log;
  EXPECT_TRUE(fs::is_symlink(c / "checkpoint.bin"));  // not replaced by a run from the start

  fresh();
  std::string record = sandflow_test::read_text(c / "run.json");
  const std::size_t at = record.find("\"scene_file\": \"");
  ASSERT_NE(at, std::string::npos) << record;
  const std::size_t value = at + std::string("\"scene_file\": \"").size();
  record.erase(value, record.find('"', value) - value);
  std::ofstream(c / "run.json") << record;
  EXPECT_EQ(bounded("run --resume " + c.string() + " --frames 2", &log), 2) << log;
  EXPECT_TRUE(has(log, "run.json: scene_file \"\" names no file")) << log;
}

// An output folder under a file, or a link to nothing, is the user's mistake (exit 2), named as
// such: it was exit 4, "cannot create the output folder: File exists".
TEST(HostileInputs, AnOutputFolderUnderAFileOrALinkToNothingIsRefused) {
  Sandbox box;
  const fs::path scene = box.write("tiny.toml", sandflow_test::tiny_block_scene(20));
  box.write("afile", "x");
  std::string log;
  EXPECT_EQ(
      bounded("run " + scene.string() + " --frames 1 --out " + (box.dir / "afile" / "sub").string(),
              &log),
      2)
      << log;
  EXPECT_TRUE(has(log, "afile is a file, not a folder")) << log;
  fs::create_symlink("/nonexistent/sandflow-out", box.dir / "dangling");
  EXPECT_EQ(
      bounded("run " + scene.string() + " --frames 1 --out " + (box.dir / "dangling").string(),
              &log),
      2)
      << log;
  EXPECT_TRUE(has(log, "the output folder is a link to nothing (/nonexistent/sandflow-out)"))
      << log;
}

// A mesh file that is a link to nothing (a loop, or storage not mounted) is said to be one, not
// "not found" (which sent the user to fetch_meshes.sh, or let fallback = "box" stand in).
TEST(HostileInputs, AMeshFileLinkedToNothingIsNamedSo) {
  Sandbox box;
  fs::create_symlink("loop.obj", box.dir / "loop.obj");
  const auto scene = box.write("loop.toml", mesh_scene("loop.obj", "fallback = \"box\""));
  std::string log;
  EXPECT_EQ(bounded("run " + scene.string() + " --check", &log), 2) << log;
  EXPECT_TRUE(has(log, "loop.obj: the mesh file is a link to nothing (loop.obj)")) << log;
}

// A resumed run whose frames before its checkpoint were deleted by hand goes on, and says which
// are missing (they cannot be written again): it said nothing and ended "finished" with holes.
TEST(HostileInputs, AResumeSaysWhichFramesBeforeItsCheckpointAreMissing) {
  Sandbox box;
  const fs::path scene = box.write("tiny.toml", sandflow_test::tiny_block_scene(20));
  const fs::path out = box.dir / "out";
  std::string log;
  ASSERT_EQ(
      bounded("run " + scene.string() + " --frames 3 --export ply --out " + out.string(), &log), 0)
      << log;
  fs::remove(out / "frames" / "0002.ply");
  EXPECT_EQ(bounded("run --resume " + out.string() + " --frames 4", &log), 0) << log;
  EXPECT_TRUE(has(log,
                  "1 of its 3 frames before the checkpoint is missing from frames/ (frame "
                  "2): the run goes on from frame 4 and cannot write it again"))
      << log;
  EXPECT_TRUE(fs::exists(out / "frames" / "0004.ply"));
}

// A finished run whose summary.json was edited into something else is not taken as finished: its
// resume reads the run back from the checkpoint and writes the summary again, the same state.
TEST(HostileInputs, ADamagedSummaryIsWrittenAgainByTheResume) {
  Sandbox box;
  std::string log;
  const fs::path out = one_frame_run(box, &log);
  ASSERT_FALSE(out.empty()) << log;
  const std::string summary = sandflow_test::read_text(out / "summary.json");
  const std::size_t at = summary.find("\"state_hash\"");
  ASSERT_NE(at, std::string::npos) << summary;
  const std::string hash = summary.substr(at, 40);
  for (const std::string damaged : {"{}", "[1, 2]", "not json"}) {
    std::ofstream(out / "summary.json") << damaged;
    EXPECT_EQ(bounded("run --resume " + out.string(), &log), 0) << damaged << "\n" << log;
    EXPECT_FALSE(has(log, "this run is finished")) << damaged << "\n" << log;
    EXPECT_TRUE(has(sandflow_test::read_text(out / "summary.json"), hash)) << damaged;
  }
}

}  // namespace

// The standard streams are the user's to point anywhere: a log on a full disk loses its lines,
// not the run (fmt threw at the first progress line, and again from main's error handler: abort,
// 134); a summary that cannot be printed is an output error (it was lost with status 0); a stream
// that was closed is /dev/null (else the next file opened takes its descriptor).
TEST(HostileInputs, StandardStreamsOnAFullDiskOrClosedLoseLinesNotTheRun) {
  Sandbox box;
  const fs::path scene = box.write("s.toml", sandflow_test::tiny_block_scene(20));
  const auto run_with = [&](const std::string& name, const std::string& streams) {
    const fs::path out = box.dir / name;
    const std::string command = "timeout 30 " + std::string(SANDFLOW_BINARY) + " run " +
                                scene.string() + " --frames 2 --out " + out.string() + " " +
                                streams;
    const int rc = std::system(command.c_str());
    EXPECT_TRUE(fs::exists(out / "summary.json")) << name;
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : 128 + WTERMSIG(rc);
  };
  EXPECT_EQ(run_with("stderr-full", "> /dev/null 2> /dev/full"), 0);
  const fs::path log = box.dir / "stdout-full.log";
  EXPECT_EQ(run_with("stdout-full", "> /dev/full 2> " + log.string()), 4);
  EXPECT_TRUE(has(sandflow_test::read_text(log),
                  "output error: the standard output could not be written (No space left on "
                  "device): the command's printed summary is lost; its files are written"))
      << sandflow_test::read_text(log);
  EXPECT_EQ(run_with("closed", ">&- 2>&- <&-"), 0);
}

// A small stack is the user's too: the readers of scenes, frames and images kept a 64 KiB buffer
// on it (a segmentation fault reading the scene under `ulimit -s 64`).
TEST(HostileInputs, ASmallStackRunsTheSceneAndReadsItsFrames) {
  if (sandflow::test::kSanitizers) GTEST_SKIP() << "AddressSanitizer needs more stack than 64 KiB";
  Sandbox box;
  const fs::path scene = box.write("s.toml", sandflow_test::tiny_block_scene(20));
  const fs::path out = box.dir / "run";
  std::string log;
  ASSERT_EQ(bounded("run " + scene.string() + " --frames 2 --out " + out.string(), &log), 0);
  for (const std::string& command :
       {"run " + scene.string() + " --frames 2 --force --out " + out.string(),
        "measure " + out.string()}) {
    const int rc = std::system(("ulimit -s 64 && timeout 30 " + std::string(SANDFLOW_BINARY) + " " +
                                command + " > " + (box.dir / "log").string() + " 2>&1")
                                   .c_str());
    EXPECT_EQ(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, 0) << command << "\n"
                                                       << sandflow_test::read_text(box.dir / "log");
  }
}

// What the environment holds changes how a run goes (its threads, where its cache is), never what
// it computes: under each setting a user or a job scheduler may leave, the run ends as it does
// without it, to the bit (OMP_NUM_THREADS=100000 crashed libgomp). The threads a run reports are
// checked in Cli.ThreadsComeFrom..., a small stack in ASmallStackRunsTheSceneAndReadsItsFrames.
TEST(HostileInputs, TheEnvironmentChangesNoResult) {
  Sandbox box;
  const fs::path scene = box.write("s.toml", sandflow_test::tiny_block_scene(40));
  const auto state_hash = [&](const std::string& name, const std::string& prefix) {
    const fs::path out = box.dir / name;
    const std::string command = prefix + " timeout 60 " + std::string(SANDFLOW_BINARY) + " run " +
                                scene.string() + " --frames 3 --out " + out.string() + " > " +
                                (box.dir / "log").string() + " 2>&1";
    const int rc = std::system(command.c_str());
    EXPECT_EQ(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, 0) << prefix << "\n"
                                                       << sandflow_test::read_text(box.dir / "log");
    const std::string summary = sandflow_test::read_text(out / "summary.json");
    const std::size_t at = summary.find("\"state_hash\"");
    return at == std::string::npos ? std::string("(none)") : summary.substr(at, 32);
  };
  const std::string want = state_hash("plain", "");
  ASSERT_NE(want, "(none)");
  const std::vector<std::string> settings = {
      "OMP_DYNAMIC=true",          "OMP_THREAD_LIMIT=1",
      "OMP_NUM_THREADS=2,2",       "OMP_NUM_THREADS=",
      "OMP_NUM_THREADS=100000",    "OMP_NUM_THREADS=1",
      "OMP_STACKSIZE=abc",         "OMP_PROC_BIND=true",
      "OMP_SCHEDULE=static,1",     "OMP_WAIT_POLICY=active",
      "GOMP_SPINCOUNT=0",          "OMP_MAX_ACTIVE_LEVELS=0",
      "OMP_CANCELLATION=true",     "TMPDIR=/nonexistent",
      "-u HOME -u XDG_CACHE_HOME", "LC_ALL=C.UTF-8 TZ=Pacific/Kiritimati"};
  for (std::size_t k = 0; k < settings.size(); ++k)
    EXPECT_EQ(state_hash("env" + std::to_string(k), "env " + settings[k]), want) << settings[k];
  for (const std::string shell : {"umask 077 &&", "ulimit -n 20 &&"})
    EXPECT_EQ(state_hash("shell" + std::to_string(shell.size()), shell), want) << shell;
}

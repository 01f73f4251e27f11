// The frame reader (read_ply, behind `sandflow measure` and `render`) on hostile files: the
// malformed corpus tests/data/frames/bad/ (written by make_frames.py, also the fuzzing seeds) must
// each raise InputError naming the file, the place ("header line N", "line N" in ascii data,
// "byte N" in binary data) and what is wrong; the valid frames beside it read back exactly.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "io/ply.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;

std::string frame_path(const std::string& name) {
  return std::string(SANDFLOW_SOURCE_DIR) + "/tests/data/frames/" + name;
}

TEST(PlyCorpus, ValidFramesReadInBothEncodings) {
  for (const char* name : {"frame_binary.ply", "frame_ascii.ply"}) {
    const FrameData f = read_ply(frame_path(name));
    ASSERT_EQ(f.size(), 3u) << name;
    // make_frames.py's third grain: (0.005, 0.009, 0.005), r = 0.0045, id 9, state 2
    EXPECT_FLOAT_EQ(static_cast<float>(f.position[2].y), 0.009f) << name;
    EXPECT_FLOAT_EQ(static_cast<float>(f.radius[2]), 0.0045f) << name;
    EXPECT_FLOAT_EQ(static_cast<float>(f.velocity[0].z), -0.5f) << name;
    EXPECT_EQ(f.id[2], 9u) << name;
    EXPECT_EQ(f.state[2], 2) << name;
  }
}

struct BadFrame {
  const char* name;
  const char* position;  ///< after "PATH: "
  const char* what;
};

constexpr BadFrame kBadFrames[] = {
    {"empty.ply", "header line 1", "not a PLY file (expected the first line 'ply')"},
    {"not_ply.ply", "header line 1", "not a PLY file"},
    {"binary_garbage.ply", "header line 1", "not a PLY file"},
    {"no_end_header.ply", "header line 14",
     "the header has no 'end_header' line (file truncated?)"},
    {"no_format.ply", "header line 4", "no 'format' line before 'end_header'"},
    {"big_endian.ply", "header line 2", "binary_big_endian PLY is not supported"},
    {"unknown_format.ply", "header line 2", "unknown format 'binary_middle_endian'"},
    {"negative_count.ply", "header line 3", "element count '-3' is not a non-negative integer"},
    {"count_not_a_number.ply", "header line 3", "element count 'many' is not a non-negative"},
    {"huge_count_10_12.ply", "header line 4",
     "declares 1000000000000 records, more than the limit of 2000000000 grains"},
    {"huge_count_u64.ply", "header line 4",
     "declares 18446744073709551615 records, more than the limit of 2000000000 grains"},
    {"count_exceeds_data.ply", "header line 4",
     "declares 1000 records but only 99 bytes of data follow the header"},
    {"count_exceeds_ascii_data.ply", "header line 3",
     "declares 1 records but only 6 bytes of data follow the header"},
    {"truncated_binary.ply", "header line 4", "declares 3 records but only 94 bytes"},
    {"truncated_ascii.ply", "line 12", "element 'vertex' record 1: unexpected end of data"},
    {"nan_position.ply", "line 10", "vertex 1: position or velocity is not finite"},
    {"inf_velocity.ply", "byte 290", "vertex 1: position or velocity is not finite"},
    {"negative_radius.ply", "line 11", "vertex 2: radius -0.005 is not a positive number"},
    {"zero_radius.ply", "byte 290", "vertex 1: radius 0 is not a positive number"},
    {"no_radius.ply", "header line 4", "vertex element has no 'radius' property"},
    {"no_x.ply", "header line 4", "vertex element has no 'x' property"},
    {"no_vertex_element.ply", "header line 5", "no 'vertex' element"},
    {"non_numeric.ply", "line 11", "element 'vertex' record 1: 'zero' is not a number"},
    {"bad_state.ply", "line 11", "vertex 0: state is not 0, 1 or 2"},
    {"bad_id.ply", "line 11", "vertex 0: id is not an unsigned 32-bit integer"},
    {"list_runs_past_end.ply", "byte 216",
     "element 'vertex' record 0: list runs past the end of the file"},
    {"bad_list_length.ply", "line 11", "element 'vertex' record 0: bad list length"},
    {"property_before_element.ply", "header line 3", "property before any element"},
    {"unknown_property_type.ply", "header line 7", "unknown property type 'flaot'"},
    {"float_list_count.ply", "header line 8", "list count type 'float' is not an integer type"},
    {"duplicate_property.ply", "header line 9", "duplicate property 'x'"},
    {"vertex_list_property.ply", "header line 4", "vertex property 'x' is a list"},
    {"unexpected_header_word.ply", "header line 3", "unexpected 'vertex'"},
};

TEST(PlyCorpus, MalformedFramesGiveClearErrors) {
  for (const BadFrame& bad : kBadFrames) {
    const std::string path = frame_path(std::string("bad/") + bad.name);
    ASSERT_TRUE(fs::exists(path)) << path;
    try {
      read_ply(path);
      ADD_FAILURE() << "no error for " << bad.name;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind(path + ": " + bad.position + ": ", 0), 0u) << msg;
      EXPECT_NE(msg.find(bad.what), std::string::npos) << bad.what << " in " << msg;
    }
  }
}

TEST(PlyCorpus, EveryCorpusFileIsListed) {
  std::set<std::string> listed;
  for (const BadFrame& bad : kBadFrames) listed.insert(bad.name);
  for (const auto& entry : fs::directory_iterator(frame_path("bad")))
    EXPECT_TRUE(listed.count(entry.path().filename().string()))
        << entry.path() << " is not in kBadFrames: give it its expected message";
}

TEST(PlyCorpus, BytesEntryPointGivesTheSameResult) {
  const auto bytes = [](const std::string& path) {
    std::stringstream ss;
    ss << std::ifstream(path, std::ios::binary).rdbuf();
    return ss.str();
  };
  try {
    parse_frame_ply(bytes(frame_path("bad/negative_radius.ply")), "mem.ply");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "mem.ply: line 11: vertex 2: radius -0.005 is not a positive number");
  }
  EXPECT_EQ(parse_frame_ply(bytes(frame_path("frame_ascii.ply")), "a.ply").radius,
            read_ply(frame_path("frame_ascii.ply")).radius);
}

TEST(PlyCorpus, DevicesAreRefusedNotReadForever) {
  // /dev/zero never ends: reading it would fill the memory
  try {
    read_ply("/dev/zero");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "/dev/zero: the frame is a character device, not a file");
  }
}

}  // namespace
}  // namespace sandflow

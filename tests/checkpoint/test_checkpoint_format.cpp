// The checkpoint file as input: truncated, corrupted, of another version or scene, or hostile
// (counts that would allocate terabytes, indices out of range) — each refused with an InputError
// that names the file and what is wrong, never a crash (the suite also runs under ASan+UBSan).
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstring>
#include <limits>
#include <random>
#include <string>

#include "checkpoint/checkpoint.hpp"
#include "core/error.hpp"
#include "sim/world.hpp"
#include "support/test_scenes.hpp"

namespace sandflow {
namespace {

SceneConfig tiny_scene(Mode mode) {
  SceneConfig s;
  s.path = "tiny";
  s.simulation.mode = mode;
  s.simulation.dt_fraction = 0.2;
  s.material.diameter = 0.01;
  s.material.diameter_spread = 0.1;
  s.output.fps = 120;
  s.geometry = {test::floor_plane()};
  EmitterConfig pile;
  pile.type = EmitterType::Lattice;
  pile.center = {0, 0, 0.02};
  pile.size = {0.06, 0.06, 0.03};
  pile.count = 40;
  s.emitters = {pile, test::disk_pour({0, 0, 0.08}, 0.02, 300, 20, {0, 0, -1})};
  return s;
}

/// A checkpoint of the tiny scene after a few frames, and the hash it was written with.
struct Sample {
  SceneConfig scene;
  std::string bytes;
  std::uint64_t hash = 0;
};

Sample sample(Mode mode = Mode::Surface) {
  Sample s;
  s.scene = tiny_scene(mode);
  World w(s.scene);
  Checkpoint c;
  for (int f = 0; f < 3; ++f) c.frames.push_back(w.advance_frame());
  s.hash = c.scene_hash = scene_hash(w, "start");
  c.world = w.save_state();
  s.bytes = encode_checkpoint(c);
  return s;
}

// ---- the layout, as the header says (checkpoint.hpp) --------------------------------------------

std::uint32_t get_u32(const std::string& b, std::size_t at) {
  std::uint32_t v = 0;
  for (int k = 0; k < 4; ++k) v |= static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + k])) << (8 * k);
  return v;
}
void put_u32(std::string& b, std::size_t at, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) b[at + k] = static_cast<char>((v >> (8 * k)) & 0xff);
}
void put_u64(std::string& b, std::size_t at, std::uint64_t v) {
  for (int k = 0; k < 8; ++k) b[at + k] = static_cast<char>((v >> (8 * k)) & 0xff);
}
std::uint32_t crc(const std::string& b, std::size_t from, std::size_t n) {
  return static_cast<std::uint32_t>(
      crc32_z(crc32_z(0, nullptr, 0), reinterpret_cast<const Bytef*>(b.data() + from), n));
}
std::size_t header_length(const std::string& b) { return get_u32(b, 12); }
/// Offset of the payload CRC: after magic, format, header length, version, hash, frame, step,
/// the section count and six (tag, size) entries.
std::size_t payload_crc_at(const std::string& b) { return 20 + get_u32(b, 16) + 8 + 8 + 8 + 4 + 6 * 12; }
/// Where section k starts (0 RUN, 1 WRLD, 2 GRNS, 3 STAT, 4 DEM, 5 SURF).
std::size_t section_at(const std::string& b, int k) {
  std::size_t at = header_length(b);
  const std::size_t table = payload_crc_at(b) - 6 * 12;
  for (int q = 0; q < k; ++q) {
    std::uint64_t size = 0;
    for (int i = 0; i < 8; ++i)
      size |= static_cast<std::uint64_t>(static_cast<unsigned char>(b[table + 12 * q + 4 + i])) << (8 * i);
    at += size;
  }
  return at;
}
/// Makes both checksums right again after an edit: what a hostile file would do.
void reseal(std::string& b) {
  const std::size_t h = header_length(b);
  put_u32(b, payload_crc_at(b), crc(b, h, b.size() - h));
  put_u32(b, h - 4, crc(b, 0, h - 4));
}

/// The last main-body slot of column 0 of a static store's compact form.
std::size_t state_last(const StaticStore::State& t) {
  return t.column_slots[0] - 1;
}

std::string parse_error(const std::string& bytes) {
  try {
    parse_checkpoint(bytes, "ck.bin");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

/// The message of restoring `bytes` into a fresh World of `scene` ("" when it is accepted).
std::string restore_error(const SceneConfig& scene, const std::string& bytes, std::uint64_t hash) {
  World w(scene);
  try {
    restore_checkpoint(w, parse_checkpoint(bytes, "ck.bin"), hash, "ck.bin");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(CheckpointFormat, AGoodCheckpointParsesAndRestores) {
  const Sample s = sample();
  EXPECT_EQ(restore_error(s.scene, s.bytes, s.hash), "");
  const Checkpoint c = parse_checkpoint(s.bytes, "ck.bin");
  EXPECT_EQ(c.world.frame, 3);
  EXPECT_EQ(c.frames.size(), 3u);
  EXPECT_EQ(c.sandflow_version, SANDFLOW_VERSION);
}

TEST(CheckpointFormat, EveryTruncationIsRefusedByName) {
  const Sample s = sample();
  for (std::size_t n = 0; n < s.bytes.size(); n += (n < 400 ? 1 : 97)) {
    const std::string msg = parse_error(s.bytes.substr(0, n));
    ASSERT_NE(msg, "") << "accepted " << n << " of " << s.bytes.size() << " bytes";
    EXPECT_EQ(msg.rfind("ck.bin: ", 0), 0u) << msg;
  }
  EXPECT_NE(parse_error(s.bytes.substr(0, s.bytes.size() - 1)).find("truncated"),
            std::string::npos);
  EXPECT_NE(parse_error(s.bytes + "x").find("trailing bytes"), std::string::npos);
}

TEST(CheckpointFormat, AnyFlippedByteIsCaughtByTheChecksums) {
  const Sample s = sample();
  for (std::size_t at = 0; at < s.bytes.size(); at += 13) {
    std::string b = s.bytes;
    b[at] = static_cast<char>(b[at] ^ 0x10);
    EXPECT_NE(parse_error(b), "") << "a flipped byte at " << at << " went unnoticed";
  }
  std::string b = s.bytes;
  b[b.size() / 2] = static_cast<char>(b[b.size() / 2] ^ 1);
  EXPECT_NE(parse_error(b).find("corrupt"), std::string::npos) << parse_error(b);
}

TEST(CheckpointFormat, GarbageAndOtherFormatsAreNamed) {
  EXPECT_NE(parse_error("").find("not a sandflow checkpoint"), std::string::npos);
  EXPECT_NE(parse_error("PK\x03\x04 some zip file").find("not a sandflow checkpoint"),
            std::string::npos);
  std::string b = sample().bytes;
  put_u32(b, 8, kCheckpointFormat + 1);
  std::string msg = parse_error(b);
  EXPECT_NE(msg.find("format version " + std::to_string(kCheckpointFormat + 1)), std::string::npos)
      << msg;
  // the format before the compact static store (4) is refused the same way
  put_u32(b, 8, 4);
  msg = parse_error(b);
  EXPECT_NE(msg.find("format version 4; this sandflow"), std::string::npos) << msg;
}

TEST(CheckpointFormat, AnotherVersionOrSceneIsRefusedWithWhatDiffers) {
  const Sample s = sample();
  // written by another sandflow
  Checkpoint c = parse_checkpoint(s.bytes, "ck.bin");
  c.sandflow_version = "9.9.9";
  std::string msg = restore_error(s.scene, encode_checkpoint(c), s.hash);
  EXPECT_NE(msg.find("written by sandflow 9.9.9, this is sandflow " SANDFLOW_VERSION),
            std::string::npos)
      << msg;
  // of another scene: the hash of the run's start record, or what the World made of it
  msg = restore_error(s.scene, s.bytes, s.hash ^ 1);
  EXPECT_NE(msg.find("written for another scene"), std::string::npos) << msg;
  World w(s.scene);
  EXPECT_NE(scene_hash(w, "start"), scene_hash(w, "start with another option"));
  SceneConfig stiffer = s.scene;
  stiffer.material.k_n *= 2;
  EXPECT_NE(scene_hash(World(stiffer), "start"), s.hash);
  // a checkpoint of a surface run is refused by the same scene in DEM mode, and the other way
  // (with a matching hash, as a crafted file would have)
  const Sample dem = sample(Mode::Dem);
  msg = restore_error(s.scene, dem.bytes, dem.hash);
  EXPECT_NE(msg.find("does not fit this scene: it has no height field"), std::string::npos) << msg;
}

TEST(CheckpointFormat, AbsurdCountsAreRefusedBeforeAllocating) {
  const Sample s = sample();
  // the grain ids' count, first field of GRNS: 2^60 entries
  std::string b = s.bytes;
  put_u64(b, section_at(b, 2), std::uint64_t{1} << 60);
  reseal(b);
  const std::string msg = parse_error(b);
  EXPECT_NE(msg.find("section 'GRNS'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("claims 1152921504606846976 entries"), std::string::npos) << msg;
  // a frame count past the data
  b = s.bytes;
  put_u64(b, section_at(b, 0), 1u << 30);
  reseal(b);
  EXPECT_NE(parse_error(b).find("section 'RUN'"), std::string::npos) << parse_error(b);
}

TEST(CheckpointFormat, IndicesOutOfRangeAreRefusedBeforeTheWorldIsTouched) {
  const Sample s = sample();
  const Checkpoint good = parse_checkpoint(s.bytes, "ck.bin");
  ASSERT_GT(good.world.dem.pairs.j.size(), 0u);
  auto refused = [&](auto&& edit, const char* expect) {
    Checkpoint c = good;
    edit(c);
    const std::string msg = restore_error(s.scene, encode_checkpoint(c), s.hash);
    EXPECT_NE(msg.find(expect), std::string::npos) << expect << ": " << msg;
  };
  refused([](Checkpoint& c) { c.world.dem.pairs.j[0] = 1u << 30; }, "pair list's row 0");
  refused([](Checkpoint& c) { c.world.dem.pairs.start.pop_back(); }, "the pair list has");
  refused(
      [](Checkpoint& c) {
        WallList& l = c.world.dem.walls;  // one more slot for the last grain, naming obstacle 7
        ++l.start.back();
        l.obstacle.push_back(7);
        l.xi.emplace_back();
        l.psi.emplace_back();
      },
      "the wall list names object 7");
  refused([](Checkpoint& c) { c.world.dem.slot_of_id[0] = 123456; }, "slot of the last rebuild");
  refused([](Checkpoint& c) { c.world.grains.id[0] = c.world.grains.id[1]; }, "appears twice");
  refused([](Checkpoint& c) { c.world.grains.x[0].z = 1e200; }, "out of range");
  refused([](Checkpoint& c) { c.world.grains.r[0] *= 10; }, "out of range");
  refused([](Checkpoint& c) { c.world.next_id += 1; }, "were emitted");
  refused([](Checkpoint& c) { c.world.emitters.pop_back(); }, "emitters");
  // counts whose sums would overflow (found by fuzz_checkpoint; UBSan in the sanitizer build)
  refused(
      [](Checkpoint& c) {
        c.world.emitters[0].emitted = 7022836102411059240;
        c.world.emitters[0].left_out = 7956002802384270447;
      },
      "emitter 0's progress is out of range");
  refused([](Checkpoint& c) { c.world.left = std::numeric_limits<std::int64_t>::max(); },
          "left the domain");
  refused([](Checkpoint& c) { c.world.surface->columns.h.pop_back(); }, "height-field array");
  refused([](Checkpoint& c) { c.world.step += 1; }, "a frame has");
  refused([](Checkpoint& c) { c.frames.pop_back(); }, "statistics of 2 frames");
}

TEST(CheckpointFormat, StaticGrainsTakeTwelveBytesEachAndTheirLayoutIsChecked) {
  // a bed of 20,000 static grains in the sample's columns: STAT holds the store's compact form,
  // 12 bytes a slot (id and code), 4 a column and 4 a tail grain, so a checkpoint of a big bed is
  // proportionally small
  const Sample s = sample();
  Checkpoint c = parse_checkpoint(s.bytes, "ck.bin");
  const World w(s.scene);
  const StaticFrame& f = w.static_grains().frame();
  const auto nc = static_cast<std::uint32_t>(f.columns());
  StaticStore st(f);
  for (GrainId k = 0; k < 20000; ++k) {
    const std::uint32_t col = k % nc;
    const Vec3 x{f.x0 + f.cell * ((col % f.nx) + 0.5), f.y0 + f.cell * ((col / f.nx) + 0.5),
                 0.005 + 0.01 * (k / nc)};
    st.add(k, x, 0.005, col);
  }
  c.world.statics = st.save_state();
  const StaticStore::State& state = c.world.statics;
  const std::string b = encode_checkpoint(c);
  const std::size_t stat = section_at(b, 4) - section_at(b, 3);
  EXPECT_EQ(stat,
            5 * 8 + 4 * std::size_t{nc} + 12 * state.id.size() + 4 * state.tail_column.size());
  EXPECT_LT(static_cast<double>(stat - 4 * nc) / 20000, 12.1);
  const Checkpoint back = parse_checkpoint(b, "ck.bin");
  EXPECT_EQ(back.world.statics.column_slots, state.column_slots);
  EXPECT_EQ(back.world.statics.id, state.id);
  EXPECT_EQ(back.world.statics.code, state.code);
  EXPECT_EQ(back.world.statics.tail_column, state.tail_column);
  EXPECT_EQ(back.world.statics.capacity, state.capacity);

  // a layout the store would not have made is refused before anything else of it is believed
  auto refused = [&](auto&& edit, const char* expect) {
    Checkpoint e = c;
    edit(e.world.statics);
    const std::string msg = restore_error(s.scene, encode_checkpoint(e), s.hash);
    EXPECT_NE(msg.find(expect), std::string::npos) << expect << ": " << msg;
  };
  ASSERT_GT(state.column_slots[0], 1u);
  refused([](StaticStore::State& t) { std::swap(t.code[0], t.code[state_last(t)]); },
          "do not ascend in height");
  ASSERT_FALSE(state.tail_column.empty());
  refused([&](StaticStore::State& t) { t.tail_column[0] = nc; }, "is filed in column");
  refused([](StaticStore::State& t) { t.column_slots.pop_back(); }, "columns of static grains");
  refused([](StaticStore::State& t) { t.capacity = std::uint64_t{1} << 40; }, "room for");
  // (and then its ids with the hot grains': this bed's 0..19999 repeat the sample's)
  refused([](StaticStore::State&) {}, "a grain id appears twice");
}

TEST(CheckpointFormat, RandomEditsNeverCrash) {
  // a hostile file: bytes changed and both checksums made right again; each is refused or, when
  // still consistent, restored and stepped — under the sanitizers, never a crash. (A World takes
  // ~30 ms to build, most of it finding the damping for the restitution: few trials.)
  for (const auto& [mode, trials] : {std::pair{Mode::Dem, 50}, std::pair{Mode::Surface, 12}}) {
    const Sample s = sample(mode);
    std::mt19937_64 rng(20240611);
    const std::size_t h = header_length(s.bytes);
    int refused = 0, accepted = 0;
    for (int trial = 0; trial < trials; ++trial) {
      std::string b = s.bytes;
      const int edits = 1 + static_cast<int>(rng() % 4);
      for (int e = 0; e < edits; ++e) {
        const std::size_t at = h + rng() % (b.size() - h);
        b[at] = static_cast<char>(rng() & 0xff);
      }
      reseal(b);
      World w(s.scene);
      try {
        restore_checkpoint(w, parse_checkpoint(b, "ck.bin"), s.hash, "ck.bin");
        ++accepted;
        w.advance_frame();
      } catch (const InputError&) {
        ++refused;
      } catch (const SimulationError&) {
        // a restored state may be nonsense that the guards stop: a clean stop too
      }
    }
    EXPECT_GT(refused, 0);
    EXPECT_EQ(refused + accepted, trials);
  }
}

}  // namespace
}  // namespace sandflow

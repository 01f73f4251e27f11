#include "checkpoint/checkpoint.hpp"

#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/file_kind.hpp"
#include "core/hash.hpp"
#include "geometry/mesh.hpp"

namespace sandflow {
namespace {

constexpr char kMagic[8] = {'S', 'A', 'N', 'D', 'C', 'K', 'P', 'T'};
constexpr std::size_t kMaxVersionLength = 64;

// The sections, in the order they are written and required.
constexpr std::array<std::uint32_t, 6> kSections = {
    0x204e5552,  // "RUN "
    0x444c5257,  // "WRLD"
    0x534e5247,  // "GRNS"
    0x54415453,  // "STAT"
    0x204d4544,  // "DEM "
    0x46525553,  // "SURF"
};

std::string tag_name(std::uint32_t tag) {
  std::string s(4, ' ');
  for (int k = 0; k < 4; ++k) {
    const char ch = static_cast<char>((tag >> (8 * k)) & 0xff);
    s[k] = ch >= 32 && ch < 127 ? ch : '?';
  }
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

std::uint32_t crc(std::string_view bytes) {
  return static_cast<std::uint32_t>(
      crc32_z(crc32_z(0, nullptr, 0), reinterpret_cast<const Bytef*>(bytes.data()), bytes.size()));
}

#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
// the fuzz build only: mutated files would rarely get past the checksums to the fields otherwise
constexpr bool kCheckChecksums = false;
#else
constexpr bool kCheckChecksums = true;
#endif

// ---- Writing ------------------------------------------------------------------------------------

class Writer {
 public:
  std::string out;

  void u8(std::uint8_t v) { out.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xff));
  }
  void u64(std::uint64_t v) {
    for (int k = 0; k < 8; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xff));
  }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void real(Real v, const char* what) {
    if (!std::isfinite(v))
      throw SimulationError(fmt::format("checkpoint: {} is not finite; the state cannot be saved",
                                        what));
    u64(std::bit_cast<std::uint64_t>(v));
  }
  void vec(const Vec3& v, const char* what) {
    real(v.x, what);
    real(v.y, what);
    real(v.z, what);
  }
  void count(std::size_t n) { u64(n); }
  void u32s(const std::vector<std::uint32_t>& a) {
    count(a.size());
    for (std::uint32_t v : a) u32(v);
  }
  void u64s(const std::vector<std::uint64_t>& a) {
    count(a.size());
    for (std::uint64_t v : a) u64(v);
  }
  void u8s(const std::vector<std::uint8_t>& a) {
    count(a.size());
    out.append(reinterpret_cast<const char*>(a.data()), a.size());
  }
  void reals(const std::vector<Real>& a, const char* what) {
    count(a.size());
    for (Real v : a) real(v, what);
  }
  void vecs(const std::vector<Vec3>& a, const char* what) {
    count(a.size());
    for (const Vec3& v : a) vec(v, what);
  }
};

void write_frame_stats(Writer& w, const FrameStats& s) {
  w.i64(s.frame);
  w.real(s.time, "a frame's time");
  w.i64(s.substeps);
  w.real(s.dt, "a frame's dt");
  for (std::int64_t v : {s.n_total, s.n_active, s.n_interface, s.n_static, s.contacts,
                         s.wall_contacts})
    w.i64(v);
  w.real(s.max_overlap_rel, "a frame's max_overlap_rel");
  w.real(s.kinetic_energy, "a frame's kinetic energy");
  for (std::int64_t v : {s.rebuilds, s.transitions.trapped, s.transitions.dislodged,
                         s.transitions.slept, s.transitions.woken, s.surface_updates,
                         s.left_domain})
    w.i64(v);
  w.real(s.wall_seconds, "a frame's wall_seconds");
  w.i64(s.transitions.woken_by_reach);
  for (Real e : {s.energy_trapped, s.energy_woken, s.energy_preloaded, s.energy_inside})
    w.real(e, "a frame's transition energy");
}

void write_list(Writer& w, const WallList& l, const char* what) {
  w.u32s(l.start);
  w.u32s(l.obstacle);
  w.vecs(l.xi, what);
  w.vecs(l.psi, what);
}

std::string section(std::uint32_t tag, const Checkpoint& c) {
  Writer w;
  const WorldState& s = c.world;
  switch (tag) {
    case kSections[0]:  // RUN
      w.count(c.frames.size());
      for (const FrameStats& f : c.frames) write_frame_stats(w, f);
      break;
    case kSections[1]:  // WRLD
      w.u32(s.next_id);
      w.i64(s.left);
      for (std::uint64_t v : s.rng) w.u64(v);
      w.count(s.profile.seconds.size());
      for (double v : s.profile.seconds) w.real(v, "a stage's seconds");
      w.count(s.emitters.size());
      for (const Emitter::Progress& e : s.emitters) {
        w.real(e.owed, "an emitter's owed grains");
        w.real(e.next_time, "an emitter's next batch time");
        w.i64(e.emitted);
        w.i64(e.delayed);
        w.i64(e.left_out);
      }
      break;
    case kSections[2]: {  // GRNS
      const Grains& g = s.grains;
      w.u32s(g.id);
      w.count(g.state.size());
      for (GrainState st : g.state) w.u8(static_cast<std::uint8_t>(st));
      w.vecs(g.x, "a grain's position");
      w.vecs(g.v, "a grain's velocity");
      w.vecs(g.w, "a grain's spin");
      w.reals(g.r, "a grain's radius");
      w.reals(g.m, "a grain's mass");
      w.reals(g.inv_m, "a grain's 1/mass");
      w.reals(g.inv_I, "a grain's 1/inertia");
      break;
    }
    case kSections[3]:  // STAT: the store's compact form (dem/grains.hpp), 12 bytes a grain
      w.u32s(s.statics.column_slots);
      w.u32s(s.statics.id);
      w.u64s(s.statics.code);
      w.u32s(s.statics.tail_column);
      w.u64(s.statics.capacity);
      break;
    case kSections[4]: {  // DEM
      const DemState& d = s.dem;
      w.u32s(d.pairs.start);
      w.u32s(d.pairs.j);
      w.u8s(d.pairs.touch);
      w.reals(d.pairs.delta0, "a pair's rest overlap");
      w.reals(d.pairs.c_n, "a pair's damping");
      w.vecs(d.pairs.xi, "a pair's tangential history");
      w.vecs(d.pairs.psi, "a pair's rolling history");
      write_list(w, d.walls, "a wall contact's history");
      write_list(w, d.bounds, "a boundary contact's history");
      w.u32s(d.slot_of_id);
      w.vecs(d.x_at_build, "a grain's reference position");
      w.reals(d.allow, "a grain's allowance");
      w.u8(d.need_rebuild ? 1 : 0);
      w.i64(d.rebuild_count);
      break;
    }
    case kSections[5]:  // SURF
      w.u8(s.surface ? 1 : 0);
      if (s.surface) {
        const HeightField::State& hf = s.surface->columns;
        for (const auto* a : {&hf.L, &hf.H, &hf.h, &hf.R, &hf.theta, &hf.Gamma, &hf.rest, &hf.hold})
          w.reals(*a, "a height-field column");
        w.reals(s.surface->h_seen, "the interface's h");
        w.reals(s.surface->L_seen, "the interface's L");
        w.u8(s.surface->pending ? 1 : 0);
        w.count(s.surface->blows.size());
        for (const Blow& b : s.surface->blows) {
          for (Real v : {b.p, b.p0, b.px, b.py, b.m, b.d, b.z0, b.rho}) w.real(v, "a blow");
          w.i64(b.n);
        }
        w.u32s(s.surface->counted);
      }
      break;
  }
  return std::move(w.out);
}

// ---- Reading ------------------------------------------------------------------------------------

// Reads one section (or the header); every read is bounded by it and fails with a message naming
// the file, the section and what was being read.
class Reader {
 public:
  Reader(std::string_view bytes, std::string name, std::string part)
      : b_(bytes), name_(std::move(name)), part_(std::move(part)) {}

  [[noreturn]] void fail(const std::string& what) const {
    if (part_.empty()) throw InputError(fmt::format("{}: {}", name_, what));
    throw InputError(fmt::format("{}: section {}: {}", name_, part_, what));
  }
  std::size_t left() const { return b_.size() - at_; }
  std::size_t offset() const { return at_; }

  std::uint64_t uint(int bytes, const char* what) {
    if (left() < static_cast<std::size_t>(bytes))
      fail(fmt::format("truncated at byte {} while reading {}", at_, what));
    std::uint64_t v = 0;
    for (int k = 0; k < bytes; ++k)
      v |= static_cast<std::uint64_t>(static_cast<unsigned char>(b_[at_ + k])) << (8 * k);
    at_ += static_cast<std::size_t>(bytes);
    return v;
  }
  std::uint8_t u8(const char* what) { return static_cast<std::uint8_t>(uint(1, what)); }
  std::uint32_t u32(const char* what) { return static_cast<std::uint32_t>(uint(4, what)); }
  std::uint64_t u64(const char* what) { return uint(8, what); }
  std::int64_t i64(const char* what) { return static_cast<std::int64_t>(uint(8, what)); }
  std::int64_t count_value(const char* what, std::int64_t lo = 0) {
    const std::int64_t v = i64(what);
    if (v < lo) fail(fmt::format("{} = {} is below {}", what, v, lo));
    return v;
  }
  Real real(const char* what) {
    const Real v = std::bit_cast<Real>(uint(8, what));
    if (!std::isfinite(v)) fail(fmt::format("{} is not a finite number", what));
    return v;
  }
  Vec3 vec(const char* what) {
    Vec3 v;
    v.x = real(what);
    v.y = real(what);
    v.z = real(what);
    return v;
  }
  std::string_view bytes(std::size_t n, const char* what) {
    if (left() < n) fail(fmt::format("truncated at byte {} while reading {}", at_, what));
    const std::string_view s = b_.substr(at_, n);
    at_ += n;
    return s;
  }
  /// An array's length, checked against the bytes left before anything is allocated.
  std::size_t count(std::size_t element_bytes, const char* what) {
    const std::uint64_t n = u64(what);
    if (n > left() / element_bytes)
      fail(fmt::format("{} claims {} entries of {} bytes, but only {} bytes are left", what, n,
                       element_bytes, left()));
    return static_cast<std::size_t>(n);
  }
  std::vector<std::uint32_t> u32s(const char* what) {
    std::vector<std::uint32_t> a(count(4, what));
    for (auto& v : a) v = u32(what);
    return a;
  }
  std::vector<std::uint64_t> u64s(const char* what) {
    std::vector<std::uint64_t> a(count(8, what));
    for (auto& v : a) v = u64(what);
    return a;
  }
  std::vector<std::uint8_t> u8s(const char* what) {
    const std::size_t n = count(1, what);
    const std::string_view s = bytes(n, what);
    return {s.begin(), s.end()};
  }
  std::vector<Real> reals(const char* what) {
    std::vector<Real> a(count(8, what));
    for (auto& v : a) v = real(what);
    return a;
  }
  std::vector<Vec3> vecs(const char* what) {
    std::vector<Vec3> a(count(24, what));
    for (auto& v : a) v = vec(what);
    return a;
  }
  void finish() const {
    if (left() != 0) fail(fmt::format("{} bytes left over after its last field", left()));
  }

 private:
  std::string_view b_;
  std::size_t at_ = 0;
  std::string name_, part_;
};

FrameStats read_frame_stats(Reader& r) {
  FrameStats s;
  const std::int64_t frame = r.i64("a frame's number");
  if (frame < 1 || frame > std::numeric_limits<int>::max()) r.fail("a frame's number is absurd");
  s.frame = static_cast<int>(frame);
  s.time = r.real("a frame's time");
  const std::int64_t substeps = r.i64("a frame's substeps");
  if (substeps < 1 || substeps > std::numeric_limits<int>::max())
    r.fail("a frame's substeps are absurd");
  s.substeps = static_cast<int>(substeps);
  s.dt = r.real("a frame's dt");
  for (std::int64_t* v : {&s.n_total, &s.n_active, &s.n_interface, &s.n_static, &s.contacts,
                          &s.wall_contacts})
    *v = r.count_value("a frame's grain or contact count");
  s.max_overlap_rel = r.real("a frame's max_overlap_rel");
  s.kinetic_energy = r.real("a frame's kinetic energy");
  for (std::int64_t* v : {&s.rebuilds, &s.transitions.trapped, &s.transitions.dislodged,
                          &s.transitions.slept, &s.transitions.woken, &s.surface_updates,
                          &s.left_domain})
    *v = r.count_value("a frame's counter");
  s.wall_seconds = r.real("a frame's wall_seconds");
  s.transitions.woken_by_reach = r.count_value("a frame's counter");
  for (Real* e : {&s.energy_trapped, &s.energy_woken, &s.energy_preloaded, &s.energy_inside})
    *e = r.real("a frame's transition energy");
  return s;
}

WallList read_list(Reader& r, const char* what) {
  WallList l;
  l.start = r.u32s(what);
  l.obstacle = r.u32s(what);
  l.xi = r.vecs(what);
  l.psi = r.vecs(what);
  return l;
}

void read_section(std::uint32_t tag, Reader& r, Checkpoint& c) {
  WorldState& s = c.world;
  switch (tag) {
    case kSections[0]: {  // RUN
      const std::size_t n = r.count(8, "the number of frames");
      for (std::size_t k = 0; k < n; ++k) c.frames.push_back(read_frame_stats(r));
      break;
    }
    case kSections[1]: {  // WRLD
      s.next_id = r.u32("the next grain id");
      s.left = r.count_value("the grains that left the domain");
      for (auto& v : s.rng) v = r.u64("the random state");
      const std::size_t stages = r.count(8, "the number of stages");
      if (stages != s.profile.seconds.size())
        r.fail(fmt::format("{} stage timings, expected {}", stages, s.profile.seconds.size()));
      for (double& v : s.profile.seconds) v = r.real("a stage's seconds");
      const std::size_t n = r.count(32, "the number of emitters");
      for (std::size_t k = 0; k < n; ++k) {
        Emitter::Progress e;
        e.owed = r.real("an emitter's owed grains");
        e.next_time = r.real("an emitter's next batch time");
        e.emitted = r.count_value("an emitter's emitted grains");
        e.delayed = r.count_value("an emitter's delayed grains");
        e.left_out = r.count_value("an emitter's grains left out");
        s.emitters.push_back(e);
      }
      break;
    }
    case kSections[2]: {  // GRNS
      Grains& g = s.grains;
      g.id = r.u32s("the grain ids");
      for (std::uint8_t st : r.u8s("the grain states")) {
        if (st > static_cast<std::uint8_t>(GrainState::Interface))
          r.fail(fmt::format("a hot grain's state is {}, expected 0 (ACTIVE) or 1 (INTERFACE)",
                             st));
        g.state.push_back(static_cast<GrainState>(st));
      }
      g.x = r.vecs("the grain positions");
      g.v = r.vecs("the grain velocities");
      g.w = r.vecs("the grain spins");
      g.r = r.reals("the grain radii");
      g.m = r.reals("the grain masses");
      g.inv_m = r.reals("the grain 1/masses");
      g.inv_I = r.reals("the grain 1/inertias");
      break;
    }
    case kSections[3]:  // STAT
      s.statics.column_slots = r.u32s("the static grains per column");
      s.statics.id = r.u32s("the static grain ids");
      s.statics.code = r.u64s("the static grain codes");
      s.statics.tail_column = r.u32s("the static grains' tail columns");
      s.statics.capacity = r.u64("the static store's capacity");
      break;
    case kSections[4]: {  // DEM
      DemState& d = s.dem;
      d.pairs.start = r.u32s("the pair list's rows");
      d.pairs.j = r.u32s("the pair list");
      d.pairs.touch = r.u8s("the pairs' contact flags");
      d.pairs.delta0 = r.reals("the pairs' rest overlaps");
      d.pairs.c_n = r.reals("the pairs' damping");
      d.pairs.xi = r.vecs("the pairs' tangential history");
      d.pairs.psi = r.vecs("the pairs' rolling history");
      d.walls = read_list(r, "the wall list");
      d.bounds = read_list(r, "the boundary-particle list");
      d.slot_of_id = r.u32s("the slots of the last rebuild");
      d.x_at_build = r.vecs("the reference positions");
      d.allow = r.reals("the allowances");
      const std::uint8_t need = r.u8("the rebuild flag");
      if (need > 1) r.fail("the rebuild flag is neither 0 nor 1");
      d.need_rebuild = need != 0;
      d.rebuild_count = r.count_value("the rebuild count");
      break;
    }
    case kSections[5]: {  // SURF
      const std::uint8_t present = r.u8("the surface flag");
      if (present > 1) r.fail("the surface flag is neither 0 nor 1");
      if (!present) break;
      SurfaceState sf;
      HeightField::State& hf = sf.columns;
      for (auto* a : {&hf.L, &hf.H, &hf.h, &hf.R, &hf.theta, &hf.Gamma, &hf.rest, &hf.hold})
        *a = r.reals("a height-field array");
      sf.h_seen = r.reals("the interface's h");
      sf.L_seen = r.reals("the interface's L");
      const std::uint8_t pending = r.u8("the interface's waiting flag");
      if (pending > 1) r.fail("the interface's waiting flag is neither 0 nor 1");
      sf.pending = pending == 1;
      sf.blows.resize(r.count(72, "the blows"));
      for (Blow& b : sf.blows) {
        for (Real* v : {&b.p, &b.p0, &b.px, &b.py, &b.m, &b.d, &b.z0, &b.rho}) *v = r.real("a blow");
        b.n = r.count_value("a blow's grains", 1);
        if (!(b.p >= 0 && b.p0 > 0 && b.m > 0 && b.d > 0 && b.rho >= 0))
          r.fail("a blow's momentum, mass, diameters or radius are out of range");
      }
      sf.counted = r.u32s("the grains the blows counted");
      if (!std::is_sorted(sf.counted.begin(), sf.counted.end()))
        r.fail("the grains the blows counted are not in order");
      s.surface = std::move(sf);
      break;
    }
  }
  r.finish();
}

}  // namespace

std::string encode_checkpoint(const Checkpoint& c) {
  std::vector<std::string> parts;
  for (std::uint32_t tag : kSections) parts.push_back(section(tag, c));

  Writer h;
  h.out.append(kMagic, sizeof kMagic);
  h.u32(c.format);
  h.u32(0);  // header length, patched below
  h.u32(static_cast<std::uint32_t>(c.sandflow_version.size()));
  h.out += c.sandflow_version;
  h.u64(c.scene_hash);
  h.i64(c.world.frame);
  h.i64(c.world.step);
  h.u32(static_cast<std::uint32_t>(parts.size()));
  std::uint32_t payload_crc = static_cast<std::uint32_t>(crc32_z(0, nullptr, 0));
  for (std::size_t k = 0; k < parts.size(); ++k) {
    h.u32(kSections[k]);
    h.u64(parts[k].size());
    payload_crc = static_cast<std::uint32_t>(crc32_z(
        payload_crc, reinterpret_cast<const Bytef*>(parts[k].data()), parts[k].size()));
  }
  h.u32(payload_crc);
  const auto header_length = static_cast<std::uint32_t>(h.out.size() + 4);
  for (int k = 0; k < 4; ++k) h.out[12 + k] = static_cast<char>((header_length >> (8 * k)) & 0xff);
  h.u32(crc(h.out));

  std::size_t total = h.out.size();
  for (const std::string& p : parts) total += p.size();
  std::string out;
  out.reserve(total);
  out += h.out;
  for (const std::string& p : parts) out += p;
  return out;
}

Checkpoint parse_checkpoint(std::string_view bytes, const std::string& name) {
  Checkpoint c;
  Reader h(bytes, name, "");
  if (bytes.size() < sizeof kMagic || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    h.fail("not a sandflow checkpoint (it does not start with \"SANDCKPT\")");
  h.bytes(sizeof kMagic, "the magic");
  c.format = h.u32("the format version");
  if (c.format != kCheckpointFormat)
    h.fail(fmt::format("checkpoint format version {}; this sandflow ({}) reads version {}",
                       c.format, SANDFLOW_VERSION, kCheckpointFormat));
  const std::uint32_t header_length = h.u32("the header length");
  if (header_length > bytes.size())
    h.fail(fmt::format("truncated: the header claims {} bytes, the file holds {}", header_length,
                       bytes.size()));
  // the header's own checksum first, so that no field of a damaged header is believed
  if (header_length < h.offset() + 4) h.fail("the header length is absurd");
  {
    Reader t(bytes.substr(header_length - 4, 4), name, "");
    const std::uint32_t header_crc = t.u32("the header checksum");
    if (kCheckChecksums && header_crc != crc(bytes.substr(0, header_length - 4)))
      h.fail("the header is corrupt (its checksum does not match)");
  }
  const std::uint32_t version_length = h.u32("the version's length");
  if (version_length > kMaxVersionLength) h.fail("the version string is absurdly long");
  c.sandflow_version = std::string(h.bytes(version_length, "the version"));
  c.scene_hash = h.u64("the scene hash");
  const std::int64_t frame = h.i64("the frame");
  const std::int64_t step = h.i64("the step");
  if (frame < 1 || frame > std::numeric_limits<int>::max() || step < 0)
    h.fail(fmt::format("frame {} and step {} are absurd", frame, step));
  c.world.frame = static_cast<int>(frame);
  c.world.step = step;
  const std::uint32_t sections = h.u32("the number of sections");
  if (sections != kSections.size())
    h.fail(fmt::format("{} sections, expected {}", sections, kSections.size()));
  std::array<std::uint64_t, kSections.size()> sizes{};
  std::uint64_t payload = 0;
  for (std::size_t k = 0; k < kSections.size(); ++k) {
    const std::uint32_t tag = h.u32("a section tag");
    if (tag != kSections[k])
      h.fail(fmt::format("section {} is '{}', expected '{}'", k, tag_name(tag),
                         tag_name(kSections[k])));
    sizes[k] = h.u64("a section size");
    if (sizes[k] > bytes.size())
      h.fail(fmt::format("truncated: section '{}' claims {} bytes, the file holds {}",
                         tag_name(tag), sizes[k], bytes.size()));
    payload += sizes[k];
  }
  const std::uint32_t payload_crc = h.u32("the payload checksum");
  if (h.offset() + 4 != header_length) h.fail("the header length does not match its fields");
  if (payload != bytes.size() - header_length)
    h.fail(fmt::format("{}: the sections hold {} bytes, the file has {} after the header",
                       payload > bytes.size() - header_length ? "truncated" : "trailing bytes",
                       payload, bytes.size() - header_length));
  const std::string_view body = bytes.substr(header_length);
  if (kCheckChecksums && crc(body) != payload_crc)
    h.fail("the data is corrupt (its checksum does not match)");

  std::size_t at = 0;
  for (std::size_t k = 0; k < kSections.size(); ++k) {
    Reader r(body.substr(at, sizes[k]), name, "'" + tag_name(kSections[k]) + "'");
    read_section(kSections[k], r, c);
    at += sizes[k];
  }
  return c;
}

std::uint64_t scene_hash(const World& world, std::string_view start_record) {
  Hasher h;
  h.add_bytes(start_record.data(), start_record.size());
  const TimeStep& ts = world.time_step();
  h.add(ts.dt);
  h.add(ts.substeps);
  h.add(world.scene().material.k_n);
  h.add(static_cast<int>(world.scene().simulation.mode));
  h.add(world.geometry().size());
  const BoundaryParticles& b = world.dem().boundary();
  h.add(b.radius);
  h.add(b.size());
  for (const Vec3& p : b.x) h.add(p);
  // a mesh edited since the start: its particles may be the same, its inside test is not
  for (const MeshObstacle& m : world.geometry().meshes()) h.add(mesh_digest(m.mesh));
  for (const GeometryConfig& g : world.scene().geometry)
    for (Real z : g.heights.z) h.add(z);
  h.add(world.emitters().size());
  for (const Emitter& e : world.emitters()) h.add(e.count());
  if (const SurfaceFlow* sf = world.surface()) {
    const HeightField& hf = sf->height_field();
    h.add(hf.nx());
    h.add(hf.ny());
    h.add(hf.cell());
    h.add(hf.initial_terrain_hash());  // (a solid removed since changes the tops, not the scene)
    // the static store's frame: its codes mean positions and radii in it
    const StaticFrame& f = world.static_grains().frame();
    for (Real v : {f.x0, f.y0, f.cell, f.z_lo, f.z_hi, f.r_lo, f.r_hi}) h.add(v);
  }
  return h.value();
}

namespace {

// Checks a parsed state against the World it is to be restored into: everything the solver
// indexes with must be in range, so that a damaged file cannot make it read out of bounds.
void check_fits(const Checkpoint& c, const World& world, const std::string& name) {
  const WorldState& s = c.world;
  auto fail = [&](const std::string& what) {
    throw InputError(fmt::format("{}: the checkpoint does not fit this scene: {}", name, what));
  };
  const TimeStep& ts = world.time_step();
  if (s.step != static_cast<std::int64_t>(s.frame) * ts.substeps)
    fail(fmt::format("frame {} at step {}, but a frame has {} steps", s.frame, s.step,
                     ts.substeps));
  if (c.frames.size() != static_cast<std::size_t>(s.frame))
    fail(fmt::format("statistics of {} frames for frame {}", c.frames.size(), s.frame));
  for (std::size_t k = 0; k < c.frames.size(); ++k)
    if (c.frames[k].frame != static_cast<int>(k) + 1)
      fail(fmt::format("the statistics of frame {} say frame {}", k + 1, c.frames[k].frame));

  // grains: sizes, ranges, ids unique, and all of them accounted for
  const Grains& g = s.grains;
  const std::size_t n = g.size();
  for (std::size_t len : {g.state.size(), g.x.size(), g.v.size(), g.w.size(), g.r.size(),
                          g.m.size(), g.inv_m.size(), g.inv_I.size()})
    if (len != n) fail(fmt::format("the hot grains' arrays have {} and {} entries", n, len));
  // the static grains: the layout of the store (counts, columns, heights ascending, its tail),
  // before anything is decoded; a code decodes inside the store's frame whatever its bits
  const SurfaceFlow* sf = world.surface();
  if (static_cast<bool>(sf) != s.surface.has_value())
    fail(sf ? "it has no height field, but the scene runs in surface mode"
            : "it has a height field, but the scene runs in DEM mode");
  const StaticStore::State& st = s.statics;
  if (const std::string e = world.static_grains().state_error(st); !e.empty()) fail(e);
  std::size_t ns = 0;
  for (GrainId id : st.id) ns += id != StaticStore::kNoGrain;
  if (n + ns > std::numeric_limits<GrainId>::max()) fail("too many grains");
  // a grain may be at most a domain's width outside it (it left during the frame's last step);
  // along an unbounded axis, a million diameters: far beyond any grain of a run, and near enough
  // that the height field's cell indices stay far from overflowing
  Vec3 lo = world.domain_lo(), hi = world.domain_hi();
  const Real far = 1e6 * world.scene().material.diameter;
  for (int a = 0; a < 3; ++a) {
    const Real pad = std::isfinite(hi[a] - lo[a]) ? hi[a] - lo[a] : far;
    lo[a] = std::max(lo[a] - pad, -far);
    hi[a] = std::min(hi[a] + pad, far);
  }
  // radii as the emitters draw them, masses and inertias as Grains::add makes them
  const MaterialConfig& mat = world.scene().material;
  const Real r_lo = 0.5 * mat.smallest_diameter() * (1 - 1e-12);
  const Real r_hi = 0.5 * mat.largest_diameter() * (1 + 1e-12);
  auto near = [](Real a, Real b) { return std::abs(a - b) <= 1e-9 * std::abs(b); };
  for (std::size_t i = 0; i < n; ++i) {
    const Real r = g.r[i], m = mat.density * (4.0 / 3.0) * kPi * r * r * r;
    if (!(r >= r_lo && r <= r_hi) || !near(g.m[i], m) || !near(g.inv_m[i], 1 / m) ||
        !near(g.inv_I[i], 1 / (0.4 * m * r * r)) || !in_box(g.x[i], lo, hi))
      fail(fmt::format("hot grain {} has a radius, mass or position out of range", g.id[i]));
  }
  std::vector<GrainId> ids(g.id);
  for (GrainId id : st.id)
    if (id != StaticStore::kNoGrain) ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  if (std::adjacent_find(ids.begin(), ids.end()) != ids.end()) fail("a grain id appears twice");
  if (!ids.empty() && ids.back() >= s.next_id)
    fail(fmt::format("grain id {} is not below the next id {}", ids.back(), s.next_id));
  // (each bound before the sum, which could overflow otherwise)
  if (s.left < 0 || s.left > static_cast<std::int64_t>(s.next_id) ||
      static_cast<std::int64_t>(ids.size()) + s.left != s.next_id)
    fail(fmt::format("{} grains held and {} left the domain, but {} were emitted", ids.size(),
                     s.left, s.next_id));

  // emitters
  if (s.emitters.size() != world.emitters().size())
    fail(fmt::format("{} emitters, the scene has {}", s.emitters.size(),
                     world.emitters().size()));
  std::int64_t emitted = 0;
  for (std::size_t k = 0; k < s.emitters.size(); ++k) {
    const Emitter::Progress& e = s.emitters[k];
    const std::int64_t count = world.emitters()[k].count();
    if (e.emitted < 0 || e.left_out < 0 || e.emitted > count || e.left_out > count - e.emitted ||
        e.owed < 0 || e.owed > 1e12 || e.delayed < 0)
      fail(fmt::format("emitter {}'s progress is out of range", k));
    emitted += e.emitted;
  }
  if (emitted != s.next_id)
    fail(fmt::format("the emitters made {} grains, but {} were numbered", emitted, s.next_id));

  // the solver's lists: n rows each (a frame ends with a DEM step, which rebuilt them if the
  // grains changed), indices in range, rows ascending as the sweep expects
  const DemState& d = s.dem;
  auto check_rows = [&](const std::vector<std::uint32_t>& start, std::size_t slots,
                        const char* what) {
    if (start.size() != n + 1 || start[0] != 0 || start[n] != slots)
      fail(fmt::format("{} has {} rows for {} grains", what, start.size(), n));
    for (std::size_t i = 0; i < n; ++i)
      if (start[i + 1] < start[i]) fail(fmt::format("{} has a row that ends before it starts", what));
  };
  const std::size_t slots = d.pairs.j.size();
  check_rows(d.pairs.start, slots, "the pair list");
  const bool rolling = world.dem().resists_turning();
  if (d.pairs.touch.size() != slots || d.pairs.delta0.size() != slots ||
      d.pairs.c_n.size() != slots || d.pairs.xi.size() != slots ||
      d.pairs.psi.size() != (rolling ? slots : 0))
    fail("the pairs' history does not match the pair list");
  for (std::size_t i = 0; i < n; ++i)
    for (std::uint32_t q = d.pairs.start[i]; q < d.pairs.start[i + 1]; ++q) {
      const std::uint8_t t = d.pairs.touch[q];
      if (d.pairs.j[q] <= i || d.pairs.j[q] >= n ||
          (q > d.pairs.start[i] && d.pairs.j[q] <= d.pairs.j[q - 1]) ||
          (t != 0 && (!(t & kTouching) || (t & ~(kTouching | kPreloaded | kSlipping)))))
        fail(fmt::format("the pair list's row {} is malformed", i));
      // a rest overlap is a part of the grains' overlap, below both radii
      const Real d0 = d.pairs.delta0[q];
      if (!(d0 >= 0) || (t & kPreloaded ? !(d0 < 2 * r_hi) : d0 != 0))
        fail(fmt::format("the pair list's row {} has a rest overlap of {} m", i, d0));
    }
  auto check_list = [&](const WallList& l, std::size_t objects, const char* what) {
    check_rows(l.start, l.obstacle.size(), what);
    if (l.xi.size() != l.obstacle.size() || l.psi.size() != l.obstacle.size())
      fail(fmt::format("{}'s history does not match it", what));
    for (std::uint32_t o : l.obstacle)
      if (o >= objects) fail(fmt::format("{} names object {} of {}", what, o, objects));
  };
  check_list(d.walls, world.geometry().size(), "the wall list");
  check_list(d.bounds, world.dem().boundary().size(), "the boundary-particle list");
  if (d.slot_of_id.size() > s.next_id) fail("the slots of the last rebuild outnumber the grains");
  for (std::uint32_t slot : d.slot_of_id)
    if (slot != kNoSlot && slot >= n) fail("a slot of the last rebuild is out of range");
  if (d.x_at_build.size() != n || d.allow.size() != n)
    fail("the reference positions or allowances do not match the grains");
  // allowances as a rebuild clamps them (0: frozen at the last rebuild; one that moves since
  // has left it at once, which rebuilds)
  const DemParams& dp = world.dem().params();
  const Real a_min = dp.skin / 2, a_max = std::max(a_min, dp.skin_max);
  for (std::size_t i = 0; i < n; ++i)
    if (!(d.allow[i] == 0 || (d.allow[i] >= a_min && d.allow[i] <= a_max)) ||
        !in_box(d.x_at_build[i], lo, hi))
      fail("a reference position or allowance is out of range");

  // the surface flow: one entry per column (the static grains were checked against the store)
  if (!sf) return;
  const std::size_t nc = sf->height_field().columns();
  const HeightField::State& hf = s.surface->columns;
  for (const auto* a : {&hf.L, &hf.H, &hf.h, &hf.R, &hf.theta, &hf.Gamma, &hf.rest, &hf.hold})
    if (a->size() != nc)
      fail(fmt::format("a height-field array has {} columns, the grid {}", a->size(), nc));
  for (const auto* a : {&s.surface->h_seen, &s.surface->L_seen})
    if (!a->empty() && a->size() != nc)
      fail(fmt::format("the interface's memory has {} columns, the grid {}", a->size(), nc));
}

}  // namespace

void restore_checkpoint(World& world, Checkpoint c, std::uint64_t expected_hash,
                        const std::string& name) {
  if (c.sandflow_version != SANDFLOW_VERSION)
    throw InputError(fmt::format(
        "{}: written by sandflow {}, this is sandflow {}: a resumed run is only the same run with "
        "the same program; resume it with sandflow {}, or start again with --force",
        name, c.sandflow_version, SANDFLOW_VERSION, c.sandflow_version));
  if (c.scene_hash != expected_hash)
    throw InputError(fmt::format(
        "{}: written for another scene (scene hash {:016x}, this run's is {:016x}): the scene, its "
        "options or a file it reads (a mesh, a heightmap image) changed since the run started; "
        "start again with --force",
        name, c.scene_hash, expected_hash));
  check_fits(c, world, name);
  world.restore_state(std::move(c.world));
}

Checkpoint read_checkpoint(const std::string& path) {
  refuse_special_file(path, "checkpoint");
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read the checkpoint (" + ec.message() + ")");
  // The World restored from it takes at least as much again: a checkpoint larger than half the
  // machine's memory cannot be resumed here (a sparse file of 1 TB would be read whole).
  const auto memory = static_cast<std::uintmax_t>(sysconf(_SC_PHYS_PAGES)) *
                      static_cast<std::uintmax_t>(sysconf(_SC_PAGE_SIZE));
  if (size > memory / 2)
    throw InputError(fmt::format(
        "{}: the checkpoint is {} bytes, more than half of this machine's memory ({} bytes): it "
        "cannot be resumed here",
        path, size, memory));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the checkpoint");
  std::string bytes(static_cast<std::size_t>(size), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (in.gcount() != static_cast<std::streamsize>(bytes.size()))
    throw InputError(path + ": cannot read the checkpoint (it ended early)");
  return parse_checkpoint(bytes, path);
}

}  // namespace sandflow

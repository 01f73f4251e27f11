#include "io/export_formats.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <stdexcept>

#include <fmt/format.h>
#include <zlib.h>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "io/sand_colour.hpp"

namespace sandflow {
namespace {

constexpr std::array<std::pair<std::string_view, ExportFormat>, 9> kNames = {{
    {"ply", ExportFormat::Ply},
    {"vtk", ExportFormat::Vtk},
    {"geo", ExportFormat::Geo},
    {"geo_gz", ExportFormat::GeoGz},
    {"pov", ExportFormat::Pov},
    {"csv", ExportFormat::Csv},
    {"height", ExportFormat::Height},
    {"height_obj", ExportFormat::HeightObj},
    {"vdb", ExportFormat::Vdb},  // io/vdb_export.hpp
}};

void check_sizes(const FrameData& f, const char* who) {
  const std::size_t n = f.size();
  const auto ok = [n](std::size_t m, bool optional) { return m == n || (optional && m == 0); };
  if (!ok(f.radius.size(), false) || !ok(f.velocity.size(), true) || !ok(f.id.size(), true) ||
      !ok(f.state.size(), true))
    throw std::invalid_argument(std::string(who) + ": FrameData arrays have different lengths");
}

// The grain's values with the defaults of empty arrays, in the exported frame.
struct Grain {
  Vec3 x, v;
  float r;
  std::uint32_t id;
  std::uint8_t state;
};

Grain grain(const FrameData& f, std::size_t i, UpAxis up) {
  return {to_up_axis(f.position[i], up),
          f.velocity.empty() ? Vec3{} : to_up_axis(f.velocity[i], up),
          static_cast<float>(f.radius[i]), f.id.empty() ? static_cast<std::uint32_t>(i) : f.id[i],
          f.state.empty() ? std::uint8_t{0} : f.state[i]};
}

template <class T>
void put(std::string& s, T v, std::endian order) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (order != std::endian::native) std::reverse(b, b + sizeof(T));
  s.append(b, sizeof(T));
}

void put3(std::string& s, const Vec3& v, std::endian order) {
  put(s, static_cast<float>(v.x), order);
  put(s, static_cast<float>(v.y), order);
  put(s, static_cast<float>(v.z), order);
}

// Text: a float printed in its shortest exact form (what the binary formats hold).
void put_text(std::string& s, double v) {
  fmt::format_to(std::back_inserter(s), "{}", static_cast<float>(v));
}

// Text: "x y z", each as put_text writes it.
void put_text3(std::string& s, const Vec3& v) {
  put_text(s, v.x);
  s += ' ';
  put_text(s, v.y);
  s += ' ';
  put_text(s, v.z);
}

// gzip data (RFC 1952) holding `bytes`, as gunzip and Houdini read it. zlib's default level (6):
// on a frame of 20,000 grains, level 1 made a file 18 % larger in a fifth of the time, level 9 one
// 2 % smaller in 3.6 times the time.
std::string gzip(std::string_view bytes, const std::string& path) {
  z_stream zs{};
  if (deflateInit2(&zs, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) !=
      Z_OK)
    throw OutputError(path + ": cannot compress: zlib could not start");
  std::string out(deflateBound(&zs, bytes.size()), '\0');
  std::size_t read = 0, written = 0;
  constexpr std::size_t kChunk = std::size_t{1} << 30;  // zlib counts in 32 bits
  int rc = Z_OK;
  while (rc != Z_STREAM_END) {
    if (written == out.size()) out.resize(2 * out.size());
    const std::size_t in = std::min(bytes.size() - read, kChunk);
    const std::size_t room = std::min(out.size() - written, kChunk);
    zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data() + read));
    zs.avail_in = static_cast<uInt>(in);
    zs.next_out = reinterpret_cast<Bytef*>(out.data() + written);
    zs.avail_out = static_cast<uInt>(room);
    rc = deflate(&zs, read + in == bytes.size() ? Z_FINISH : Z_NO_FLUSH);
    read += in - zs.avail_in;
    written += room - zs.avail_out;
    if (rc == Z_STREAM_ERROR) {
      deflateEnd(&zs);
      throw OutputError(path + ": cannot compress: zlib failed");
    }
  }
  deflateEnd(&zs);
  out.resize(written);
  return out;
}

bool ends_with(std::string_view s, std::string_view tail) {
  return s.size() >= tail.size() && s.substr(s.size() - tail.size()) == tail;
}

}  // namespace

// ---- Choosing exports ----

std::string_view export_name(ExportFormat f) {
  for (const auto& [name, format] : kNames)
    if (format == f) return name;
  return "?";
}

std::optional<ExportFormat> export_format(std::string_view name) {
  for (const auto& [n, format] : kNames)
    if (n == name) return format;
  return std::nullopt;
}

std::string export_names() {
  std::string s;
  for (const auto& [name, format] : kNames) s += (s.empty() ? "" : ", ") + std::string(name);
  return s;
}

std::vector<ExportFormat> parse_export_list(const std::string& list, const std::string& where) {
  std::vector<std::string> words;
  std::size_t begin = 0;
  while (true) {
    const std::size_t comma = list.find(',', begin);
    std::string w = list.substr(begin, comma == std::string::npos ? comma : comma - begin);
    const auto first = w.find_first_not_of(" \t"), last = w.find_last_not_of(" \t");
    words.push_back(first == std::string::npos ? "" : w.substr(first, last - first + 1));
    if (comma == std::string::npos) break;
    begin = comma + 1;
  }
  if (words.size() == 1 && words[0] == "none") return {};
  std::vector<ExportFormat> out;
  for (const std::string& w : words) {
    if (w == "none")
      throw InputError(where + " " + list + ": \"none\" stands alone (no per-frame files)");
    const auto f = export_format(w);
    if (!f)
      throw InputError(where + " " + list + ": " +
                       (w.empty() ? std::string("an empty name") : "unknown export \"" + w + "\"") +
                       "; expected a comma-separated list of " + export_names() + ", or none");
    if (!has_export(out, *f)) out.push_back(*f);
  }
  return out;
}

std::vector<ExportFormat> run_exports(const OutputConfig& o, Mode mode,
                                      std::vector<ExportFormat>* dropped) {
  // The static bulk of a surface-mode heap is in the height field, not in the PLY frames.
  if (!o.exports)
    return mode == Mode::Surface ? std::vector{ExportFormat::Ply, ExportFormat::Height}
                                 : std::vector{ExportFormat::Ply};
  std::vector<ExportFormat> out;
  for (const ExportFormat f : *o.exports) {
    const bool height = f == ExportFormat::Height || f == ExportFormat::HeightObj;
    if (height && mode == Mode::Dem) {
      if (dropped) dropped->push_back(f);
    } else {
      out.push_back(f);
    }
  }
  return out;
}

std::string dropped_exports_warning(const std::string& scene_path,
                                    const std::vector<ExportFormat>& dropped) {
  std::string names;
  for (const ExportFormat f : dropped)
    names += (names.empty() ? "" : " and ") + std::string(export_name(f));
  return scene_path + ": export " + names +
         " skipped: height fields exist only in surface mode, this run is plain DEM";
}

bool has_export(const std::vector<ExportFormat>& list, ExportFormat f) {
  return std::find(list.begin(), list.end(), f) != list.end();
}

std::string_view up_axis_name(UpAxis up) {
  return up == UpAxis::Y ? "y" : "z";
}

// ---- Writers ----

void write_vtk_legacy(const std::string& path, const FrameData& f, UpAxis up,
                      const std::string& title) {
  check_sizes(f, "write_vtk_legacy");
  constexpr auto be = std::endian::big;
  const std::size_t n = f.size();
  std::string s;
  s.reserve(256 + 37 * n);
  std::string line1 = title.substr(0, title.find('\n'));
  line1 = line1.substr(0, 255);  // the format's limit
  fmt::format_to(std::back_inserter(s),
                 "# vtk DataFile Version 3.0\n{}\nBINARY\nDATASET POLYDATA\nPOINTS {} float\n",
                 line1, n);
  for (std::size_t i = 0; i < n; ++i) put3(s, grain(f, i, up).x, be);
  fmt::format_to(std::back_inserter(s), "\nVERTICES {} {}\n", n, 2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    put(s, std::int32_t{1}, be);
    put(s, static_cast<std::int32_t>(i), be);
  }
  fmt::format_to(std::back_inserter(s),
                 "\nPOINT_DATA {}\nSCALARS radius float 1\nLOOKUP_TABLE default\n", n);
  for (std::size_t i = 0; i < n; ++i) put(s, grain(f, i, up).r, be);
  s += "\nVECTORS velocity float\n";
  for (std::size_t i = 0; i < n; ++i) put3(s, grain(f, i, up).v, be);
  s += "\nSCALARS state unsigned_char 1\nLOOKUP_TABLE default\n";
  for (std::size_t i = 0; i < n; ++i) put(s, grain(f, i, up).state, be);
  s += "\nSCALARS id unsigned_int 1\nLOOKUP_TABLE default\n";
  for (std::size_t i = 0; i < n; ++i) put(s, grain(f, i, up).id, be);
  s += "\n";
  write_file_atomic(path, s);
}

void write_vtp(const std::string& path, const FrameData& f, UpAxis up) {
  check_sizes(f, "write_vtp");
  constexpr auto le = std::endian::little;
  const std::size_t n = f.size();
  // The appended blocks, each a UInt64 byte count and the values; `offset` is where each starts.
  std::string data;
  std::vector<std::size_t> offset;
  const auto block = [&](std::size_t bytes, auto&& fill) {
    offset.push_back(data.size());
    put(data, static_cast<std::uint64_t>(bytes), le);
    fill();
  };
  block(12 * n, [&] {
    for (std::size_t i = 0; i < n; ++i) put3(data, grain(f, i, up).x, le);
  });
  block(4 * n, [&] {
    for (std::size_t i = 0; i < n; ++i) put(data, grain(f, i, up).r, le);
  });
  block(12 * n, [&] {
    for (std::size_t i = 0; i < n; ++i) put3(data, grain(f, i, up).v, le);
  });
  block(n, [&] {
    for (std::size_t i = 0; i < n; ++i) put(data, grain(f, i, up).state, le);
  });
  block(4 * n, [&] {
    for (std::size_t i = 0; i < n; ++i) put(data, grain(f, i, up).id, le);
  });
  block(4 * n, [&] {
    for (std::size_t i = 0; i < n; ++i) put(data, static_cast<std::int32_t>(i), le);
  });
  block(4 * n, [&] {
    for (std::size_t i = 0; i < n; ++i) put(data, static_cast<std::int32_t>(i + 1), le);
  });

  std::string s;
  s.reserve(2048 + data.size());
  fmt::format_to(std::back_inserter(s),
                 "<?xml version=\"1.0\"?>\n"
                 "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
                 "header_type=\"UInt64\">\n"
                 "  <PolyData>\n"
                 "    <Piece NumberOfPoints=\"{0}\" NumberOfVerts=\"{0}\" NumberOfLines=\"0\" "
                 "NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n"
                 "      <Points>\n"
                 "        <DataArray type=\"Float32\" Name=\"Points\" NumberOfComponents=\"3\" "
                 "format=\"appended\" offset=\"{1}\"/>\n"
                 "      </Points>\n"
                 "      <PointData Scalars=\"radius\" Vectors=\"velocity\">\n"
                 "        <DataArray type=\"Float32\" Name=\"radius\" format=\"appended\" "
                 "offset=\"{2}\"/>\n"
                 "        <DataArray type=\"Float32\" Name=\"velocity\" NumberOfComponents=\"3\" "
                 "format=\"appended\" offset=\"{3}\"/>\n"
                 "        <DataArray type=\"UInt8\" Name=\"state\" format=\"appended\" "
                 "offset=\"{4}\"/>\n"
                 "        <DataArray type=\"UInt32\" Name=\"id\" format=\"appended\" "
                 "offset=\"{5}\"/>\n"
                 "      </PointData>\n"
                 "      <Verts>\n"
                 "        <DataArray type=\"Int32\" Name=\"connectivity\" format=\"appended\" "
                 "offset=\"{6}\"/>\n"
                 "        <DataArray type=\"Int32\" Name=\"offsets\" format=\"appended\" "
                 "offset=\"{7}\"/>\n"
                 "      </Verts>\n"
                 "    </Piece>\n"
                 "  </PolyData>\n"
                 "  <AppendedData encoding=\"raw\">\n   _",
                 n, offset[0], offset[1], offset[2], offset[3], offset[4], offset[5], offset[6]);
  s += data;
  s += "\n  </AppendedData>\n</VTKFile>\n";
  write_file_atomic(path, s);
}

void write_pvd(const std::string& path, const std::vector<SeriesEntry>& entries) {
  std::string s =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  for (const SeriesEntry& e : entries)
    fmt::format_to(std::back_inserter(s),
                   "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>\n", e.time,
                   e.file);
  s += "  </Collection>\n</VTKFile>\n";
  write_file_atomic(path, s);
}

std::string houdini_frame_name(int frame, bool gzip) {
  return fmt::format("sand.{:04d}.geo{}", frame + 1, gzip ? ".gz" : "");
}

void write_houdini_geo(const std::string& path, const FrameData& f, UpAxis up) {
  check_sizes(f, "write_houdini_geo");
  const std::size_t n = f.size();
  const int prims = n > 0 ? 1 : 0;
  std::string s;
  s.reserve(512 + 144 * n);
  fmt::format_to(std::back_inserter(s),
                 "PGEOMETRY V5\n"
                 "NPoints {} NPrims {}\n"
                 "NPointGroups 0 NPrimGroups 0\n"
                 "NPointAttrib 6 NVertexAttrib 0 NPrimAttrib {} NAttrib 0\n"
                 "PointAttrib\n"
                 "Cd 3 float 1 1 1\n"
                 "v 3 vector 0 0 0\n"
                 "pscale 1 float 0\n"
                 "orient 4 float 0 0 0 1\n"
                 "id 1 int 0\n"
                 "state 1 int 0\n",
                 n, prims, prims);
  std::array<std::string, kSandShades> colour;  // each shade's Cd, as text
  for (int k = 0; k < kSandShades; ++k) put_text3(colour[k], srgb_to_linear(sand_srgb(k)));
  // each point: x y z w (Cd v pscale orient id state)
  for (std::size_t i = 0; i < n; ++i) {
    const Grain g = grain(f, i, up);
    put_text3(s, g.x);
    s += " 1 (";
    s += colour[static_cast<std::size_t>(sand_shade(g.id))];
    s += ' ';
    put_text3(s, g.v);
    s += ' ';
    put_text(s, g.r);
    fmt::format_to(std::back_inserter(s), " 0 0 0 1 {} {})\n", g.id, g.state);
  }
  if (n > 0) {
    // one particle system holding every point, with the attribute Houdini gives its particles
    fmt::format_to(std::back_inserter(s), "PrimitiveAttrib\ngenerator 1 index 1 papi\nPart {}", n);
    for (std::size_t i = 0; i < n; ++i) fmt::format_to(std::back_inserter(s), " {}", i);
    s += " [0]\n";
  }
  s += "beginExtra\nendExtra\n";
  write_file_atomic(path, ends_with(path, ".gz") ? gzip(s, path) : s);
}

void write_grains_csv(const std::string& path, const FrameData& f, UpAxis up) {
  check_sizes(f, "write_grains_csv");
  const std::size_t n = f.size();
  std::string s = "id,x,y,z,radius,vx,vy,vz,state\n";
  s.reserve(s.size() + 96 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const Grain g = grain(f, i, up);
    fmt::format_to(std::back_inserter(s), "{},", g.id);
    for (const double v : {g.x.x, g.x.y, g.x.z, static_cast<double>(g.r), g.v.x, g.v.y, g.v.z}) {
      put_text(s, v);
      s += ',';
    }
    fmt::format_to(std::back_inserter(s), "{}\n", g.state);
  }
  write_file_atomic(path, s);
}

}  // namespace sandflow

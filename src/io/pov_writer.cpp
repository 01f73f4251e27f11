#include "io/pov_writer.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string_view>
#include <type_traits>

#include <fmt/format.h>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/process.hpp"
#include "core/read_file.hpp"
#include "io/media_check.hpp"
#include "io/sand_colour.hpp"

namespace sandflow {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// Text helpers

// Seven significant digits: a tenth of a micrometre on a metre-sized scene, and short lines.
void put(std::string& s, double v) {
  char buf[32];
  if (!std::isfinite(v)) v = 0;  // never write text POV-Ray cannot parse
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 7);
  s.append(buf, r.ptr);
}

template <class T>
requires std::is_integral_v<T>
void put(std::string& s, T v) {
  s += std::to_string(v);
}

void put(std::string& s, std::string_view text) {
  s.append(text);
}

void put(std::string& s, const Vec3& v) {
  s += '<';
  put(s, v.x);
  s += ',';
  put(s, v.y);
  s += ',';
  put(s, v.z);
  s += '>';
}

// A point written to the shortest text that reads back as the same double: the camera, whose
// direction seven digits of its two points may not tell.
struct Exact {
  Vec3 v;
};

void put(std::string& s, Exact e) {
  char buf[32];
  s += '<';
  for (int a = 0; a < 3; ++a) {
    const double c = std::isfinite(e.v[a]) ? e.v[a] : 0;
    const auto r = std::to_chars(buf, buf + sizeof buf, c);
    s.append(buf, r.ptr);
    s += a < 2 ? ',' : '>';
  }
}

template <class... Args>
void line(std::string& s, const Args&... args) {
  (put(s, args), ...);
  s += '\n';
}

// POV-Ray `matrix`: the images of the local x, y, z axes, then the translation.
std::string matrix(const Mat3& m, const Vec3& t) {
  std::string s = "matrix <";
  for (int col = 0; col < 3; ++col) {
    for (int row = 0; row < 3; ++row) {
      put(s, m.m[row][col]);
      s += ',';
    }
  }
  put(s, t.x);
  s += ',';
  put(s, t.y);
  s += ',';
  put(s, t.z);
  s += '>';
  return s;
}

Vec3 normalized(const Vec3& v) {
  const Real n = norm(v);
  return n > 0 ? v / n : Vec3{0, 0, 1};
}

// A rotation taking local z to `n` (local x, y span the plane).
Mat3 frame_from_normal(const Vec3& n_in) {
  const Vec3 n = normalized(n_in);
  const Vec3 a = std::abs(n.y) < 0.9 ? Vec3{0, 1, 0} : Vec3{1, 0, 0};
  const Vec3 e1 = normalized(cross(a, n));
  const Vec3 e2 = cross(n, e1);
  Mat3 m;
  for (int r = 0; r < 3; ++r) {
    m.m[r][0] = e1[r];
    m.m[r][1] = e2[r];
    m.m[r][2] = n[r];
  }
  return m;
}

// A "nice" length (1, 2 or 5 times a power of ten) close to x.
double nice_length(double x) {
  if (!(x > 0) || !std::isfinite(x)) return 1.0;
  const double p = std::pow(10.0, std::floor(std::log10(x)));
  const double m = x / p;
  return p * (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10);
}

// ---------------------------------------------------------------------------------------------
// Scene parts

// The framed box, or the frame's own when none is given; never empty.
ViewBounds scene_bounds(const FrameData& f, const std::vector<GeometryConfig>& geometry,
                        const std::vector<const TriangleMesh*>& meshes, const PovOptions& opt) {
  ViewBounds b = opt.bounds;
  if (b.empty) {
    b = grain_bounds(f);
    b.add(geometry_bounds(geometry, meshes));
  }
  if (b.empty) b.add({0, 0, 0}, 0.5);
  return b;
}

struct Camera {
  Vec3 location, look_at, sky{0, 0, 1};
};

// Only the direction of look_at counts for a perspective camera, but POV-Ray refuses one that
// lies within about 1e-10 of the location: a point that near is moved out along the view.
Vec3 pov_look_at(const Camera& cam) {
  const Vec3 view = cam.look_at - cam.location;
  const Real length = norm(view);
  if (!(length > 0) || length >= 1e-3 * std::max<Real>(1, norm(cam.location))) return cam.look_at;
  return cam.location + view / length * std::max<Real>(1, norm(cam.location));
}

void write_header(std::string& s, const Camera& cam, const ViewBounds& b, const PovOptions& opt,
                  std::size_t grains) {
  const double aspect = static_cast<double>(opt.width) / std::max(opt.height, 1);
  const double r = b.radius();
  const Vec3 c = b.centre();
  line(s, "// sandflow frame: ", grains, " grains. POV-Ray 3.7.");
  line(s, "// World: right-handed, z up (see src/io/pov_writer.hpp for the camera set-up).");
  line(s, "#version 3.7;");
  line(s, "global_settings { assumed_gamma 1.0 max_trace_level 10 }");
  line(s, "");
  line(s, "camera {");
  line(s, "  perspective");
  line(s, "  location ", Exact{cam.location});
  line(s, "  right -x*", aspect, "  // negated: right-handed world, picture not mirrored");
  line(s, "  up y");
  line(s, "  sky ", cam.sky);
  line(s, "  angle ", opt.fov_deg);
  line(s, "  look_at ", Exact{pov_look_at(cam)});
  line(s, "}");
  line(s, "");
  // Key light high on the camera's left, soft; fill light on its right, without shadows.
  const double key_dist = 8 * r;
  const Vec3 key = c + normalized({-0.25, -0.97, 1.2}) * key_dist;
  const Vec3 fill = c + normalized({1.3, -0.3, 0.7}) * key_dist;
  const double size = 0.2 * key_dist;
  if (opt.soft_light) {
    line(s, "light_source {");
    line(s, "  ", key, " color rgb 1.0");
    line(s, "  area_light <", size, ",0,0>, <0,", size,
         ",0>, 3, 3 adaptive 1 jitter circular orient");
    line(s, "}");
  } else {
    line(s, "light_source { ", key, " color rgb 1.0 }  // draft: a point light, hard shadows");
  }
  line(s, "light_source { ", fill, " color rgb 0.3 shadowless }");
  line(s, "sky_sphere {");
  line(s,
       "  pigment { gradient z color_map { [0.0 srgb <0.93,0.94,0.96>] [0.5 srgb <0.86,0.9,0.96>]"
       " [1.0 srgb <0.55,0.68,0.88>] } scale 2 translate -z }");
  line(s, "}");
  line(s, "");
  // Sand: base colour with a small, stable variation per grain; matte, no reflection.
  line(s,
       "#declare SandFinish = finish { ambient 0.05 diffuse 0.85 specular 0.06 roughness 0.06 }");
  line(s, "#declare Sand = array[", kSandShades, "] {");
  for (int k = 0; k < kSandShades; ++k)
    line(s, "  texture { pigment { srgb ", sand_srgb(k), " } finish { SandFinish } }",
         k + 1 < kSandShades ? "," : "");
  line(s, "}");
  line(s, "");
  line(s,
       "#declare Solid = texture { pigment { srgb <0.62,0.63,0.65> }"
       " finish { ambient 0.05 diffuse 0.8 specular 0.05 roughness 0.05 } }");
  line(s,
       "#declare Glass = texture { pigment { rgbf <0.96,0.98,1.0,0.9> }"
       " finish { ambient 0 diffuse 0.05 specular 0.6 roughness 0.002 reflection 0.04 } }");
  line(s, "#declare GlassInterior = interior { ior 1.45 }");
  // Floor checker: squares of a round size about an eighth of the scene, centred in z on the
  // plane so that the pattern's cell boundaries do not coincide with the surface.
  const double square = nice_length(std::max(b.hi.x - b.lo.x, b.hi.y - b.lo.y) / 8);
  line(s,
       "#declare Floor = texture { pigment { checker srgb 0.60, srgb 0.64 translate 0.5*z scale ",
       square, " } finish { ambient 0.05 diffuse 0.8 } }");
  line(s, "");
}

// A drawn plane with an upward normal: a floor the picture already has.
bool has_visible_plane(const std::vector<GeometryConfig>& geometry) {
  return std::any_of(geometry.begin(), geometry.end(), [](const GeometryConfig& g) {
    return g.type == GeometryType::Plane && g.render == RenderStyle::Solid &&
           normalized(g.normal).z > 0.5;
  });
}

std::string material(RenderStyle r) {
  return r == RenderStyle::Glass ? "texture { Glass } interior { GlassInterior }"
                                 : "texture { Solid }";
}

// A heightmap as one mesh2: the surface through the samples (every stride-th sample, so that at
// most kMaxDrawnSide a side are drawn), two triangles a cell, closed by vertical sides and a flat
// bottom. The bilinear surface the grains meet differs from these triangles by at most a quarter
// of a cell's twist |z00 - z10 - z01 + z11| (with stride 1).
constexpr int kMaxDrawnSide = 256;

void write_heightmap(std::string& s, const GeometryConfig& g, const std::string& mat) {
  const HeightGrid& h = g.heights;
  if (h.nx < 2 || h.ny < 2 || h.z.size() != static_cast<std::size_t>(h.nx) * h.ny) return;
  const int stride = std::max(1, (std::max(h.nx, h.ny) - 2) / (kMaxDrawnSide - 1) + 1);
  const auto picks = [stride](int n) {
    std::vector<int> v;
    for (int i = 0; i < n - 1; i += stride) v.push_back(i);
    v.push_back(n - 1);
    return v;
  };
  const std::vector<int> xs = picks(h.nx), ys = picks(h.ny);
  const int mx = static_cast<int>(xs.size()), my = static_cast<int>(ys.size());
  const double bottom = *std::min_element(h.z.begin(), h.z.end()) - g.base_thickness;
  const auto at = [&](int i, int j) {
    const double x = g.extent[0] + (g.extent[2] - g.extent[0]) * xs[i] / (h.nx - 1);
    const double y = g.extent[1] + (g.extent[3] - g.extent[1]) * ys[j] / (h.ny - 1);
    return Vec3{x, y, h.z[static_cast<std::size_t>(ys[j]) * h.nx + xs[i]]};
  };
  // the perimeter, counter-clockwise from (x0, y0), as (i, j) pairs
  std::vector<std::pair<int, int>> rim;
  for (int i = 0; i < mx; ++i) rim.emplace_back(i, 0);
  for (int j = 1; j < my; ++j) rim.emplace_back(mx - 1, j);
  for (int i = mx - 2; i >= 0; --i) rim.emplace_back(i, my - 1);
  for (int j = my - 2; j >= 1; --j) rim.emplace_back(0, j);
  const int top_n = mx * my, rim_n = static_cast<int>(rim.size());

  line(s, "mesh2 {");
  line(s, "  vertex_vectors { ", top_n + rim_n, ",");
  for (int j = 0; j < my; ++j)
    for (int i = 0; i < mx; ++i) line(s, "    ", at(i, j), ",");
  for (const auto& [i, j] : rim) {
    Vec3 v = at(i, j);
    v.z = bottom;
    line(s, "    ", v, ",");
  }
  line(s, "  }");
  const int faces = 2 * (mx - 1) * (my - 1) + 2 * rim_n + 2;
  line(s, "  face_indices { ", faces, ",");
  const auto tri = [&s](int a, int c, int d) { line(s, "    <", a, ",", c, ",", d, ">,"); };
  for (int j = 0; j + 1 < my; ++j)
    for (int i = 0; i + 1 < mx; ++i) {
      const int k = j * mx + i;
      tri(k, k + 1, k + mx + 1);
      tri(k, k + mx + 1, k + mx);
    }
  for (int r = 0; r < rim_n; ++r) {  // the sides: a quad under each perimeter segment
    const int q = (r + 1) % rim_n;
    const int ta = rim[r].second * mx + rim[r].first, tb = rim[q].second * mx + rim[q].first;
    tri(ta, tb, top_n + q);
    tri(ta, top_n + q, top_n + r);
  }
  // the bottom: the four corners of the perimeter
  const int c0 = top_n, c1 = top_n + mx - 1, c2 = top_n + mx - 1 + my - 1,
            c3 = top_n + 2 * (mx - 1) + my - 1;
  tri(c0, c1, c2);
  tri(c0, c2, c3);
  line(s, "  }");
  line(s, "  ", mat);
  line(s, "}");
}

// A placed mesh as one mesh2, its vertices in world coordinates.
void write_mesh(std::string& s, const TriangleMesh& m, const std::string& mat) {
  line(s, "mesh2 {");
  line(s, "  vertex_vectors { ", m.vertices.size(), ",");
  for (const Vec3& v : m.vertices) line(s, "    ", v, ",");
  line(s, "  }");
  line(s, "  face_indices { ", m.triangles.size(), ",");
  for (const auto& t : m.triangles) line(s, "    <", t[0], ",", t[1], ",", t[2], ">,");
  line(s, "  }");
  line(s, "  ", mat);
  line(s, "}");
}

void write_geometry(std::string& s, const GeometryConfig& g, const ViewBounds& b,
                    const TriangleMesh* mesh) {
  if (g.render == RenderStyle::Hidden) return;
  const bool glass = g.render == RenderStyle::Glass;
  const std::string mat = material(g.render);
  if (!g.name.empty()) line(s, "// ", g.name);
  switch (g.type) {
    case GeometryType::Plane: {
      // Local frame: z along the normal, origin at the point nearest the scene's centre.
      const Vec3 n = normalized(g.normal);
      const Vec3 origin = b.centre() - n * dot(b.centre() - g.point, n);
      const std::string m = matrix(frame_from_normal(n), origin);
      if (glass) {
        const double half = 1.5 * b.radius(), t = 0.01 * b.radius();
        line(s, "box { <", -half, ",", -half, ",", -t, ">, <", half, ",", half, ",0> ", mat, " ", m,
             " }");
      } else {
        line(s, "plane { z, 0 texture { Floor } ", m, " }");
      }
      break;
    }
    case GeometryType::Sphere:
      line(s, "sphere { ", g.center, ", ", g.radius, " ", mat, " }");
      break;
    case GeometryType::Box: {
      const std::string m = matrix(rotation_xyz_deg(g.rotation_deg), g.center);
      const Vec3 h = g.size * 0.5;
      if (!g.container) {
        line(s, "box { ", -h, ", ", h, " ", mat, " ", m, " }");
        break;
      }
      // Walls around the inner size; an open top cuts the inner box through the lid.
      const double t = g.wall_thickness;
      const Vec3 out_lo{-h.x - t, -h.y - t, -h.z - t};
      const Vec3 out_hi{h.x + t, h.y + t, g.open_top ? h.z : h.z + t};
      const Vec3 in_hi{h.x, h.y, g.open_top ? h.z + t : h.z};
      line(s, "difference { box { ", out_lo, ", ", out_hi, " } box { ", -h, ", ", in_hi, " } ", mat,
           " ", m, " }");
      break;
    }
    case GeometryType::Cylinder: {
      const std::string m = matrix(rotation_xyz_deg(g.rotation_deg), g.center);
      const double hz = 0.5 * g.height;
      if (!g.container) {
        line(s, "cylinder { <0,0,", -hz, ">, <0,0,", hz, ">, ", g.radius, " ", mat, " ", m, " }");
        break;
      }
      // Tube and bottom (and lid unless open_top) around the inner radius and height.
      const double t = g.wall_thickness;
      const double out_top = g.open_top ? hz : hz + t;
      const double in_top = g.open_top ? hz + t : hz;
      line(s, "difference { cylinder { <0,0,", -hz - t, ">, <0,0,", out_top, ">, ", g.radius + t,
           " } cylinder { <0,0,", -hz, ">, <0,0,", in_top, ">, ", g.radius, " } ", mat, " ", m,
           " }");
      break;
    }
    case GeometryType::Bowl: {
      // the shell between the two spheres, below the rim plane (POV-Ray's plane { z, h } is the
      // half-space z <= h)
      const std::string m = matrix(rotation_xyz_deg(g.rotation_deg), g.center);
      const double rim = g.depth.value_or(g.radius) - g.radius;
      line(s, "intersection { difference { sphere { <0,0,0>, ", g.radius + g.wall_thickness,
           " } sphere { <0,0,0>, ", g.radius, " } } plane { z, ", rim, " } ", mat, " ", m, " }");
      break;
    }
    case GeometryType::Heightmap:
      write_heightmap(s, g, mat);
      break;
    case GeometryType::Mesh:
      if (mesh) write_mesh(s, *mesh, mat);
      break;
  }
}

// The grains as one union of spheres per sand shade, its texture given once: POV-Ray parsed a
// 202,362-grain frame in 0.48 s this way against 1.78 s as a macro call a grain, and held 98 MB
// against 237 MB with a texture for every sphere (docs/performance.md, 2026-12-02, sixty-first).
// A shade with a single grain is a textured sphere (POV-Ray warns of a union of one).
void write_grains(std::string& s, const FrameData& f) {
  std::array<std::vector<std::uint32_t>, kSandShades> by_shade;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (!is_finite(f.position[i]) || !(f.radius[i] > 0)) continue;
    const std::uint32_t id = f.id.empty() ? static_cast<std::uint32_t>(i) : f.id[i];
    by_shade[static_cast<std::size_t>(sand_shade(id))].push_back(static_cast<std::uint32_t>(i));
  }
  line(s, "// grains: a union of spheres per sand shade, sphere{<x,y,z>,radius}");
  for (int k = 0; k < kSandShades; ++k) {
    const std::vector<std::uint32_t>& grains = by_shade[static_cast<std::size_t>(k)];
    if (grains.empty()) continue;
    const bool alone = grains.size() == 1;
    if (!alone) line(s, "union {  // Sand[", k, "]");
    for (const std::uint32_t i : grains) {
      s += "sphere{<";
      put(s, f.position[i].x);
      s += ',';
      put(s, f.position[i].y);
      s += ',';
      put(s, f.position[i].z);
      s += ">,";
      put(s, f.radius[i]);
      s += alone ? fmt::format(" texture{{Sand[{}]}}}}\n", k) : std::string("}\n");
    }
    if (!alone) line(s, "texture { Sand[", k, "] } }");
  }
}

std::string tail_of(const std::string& path, std::size_t max_chars) {
  std::string text;
  try {
    text = read_whole_file(path, "log", kAnyFileSize);
  } catch (const InputError&) {
    return "";  // (no log to show: the caller's message stands alone)
  }
  if (text.size() > max_chars) text = "..." + text.substr(text.size() - max_chars);
  return text;
}

}  // namespace

void ViewBounds::add(const Vec3& p, Real r) {
  const Vec3 e{r, r, r};
  if (empty) {
    lo = p - e;
    hi = p + e;
    empty = false;
  } else {
    lo = min(lo, p - e);
    hi = max(hi, p + e);
  }
}

void ViewBounds::add(const ViewBounds& b) {
  if (b.empty) return;
  add(b.lo, 0);
  add(b.hi, 0);
}

Real ViewBounds::radius() const {
  return std::max(0.5 * norm(hi - lo), Real(1e-6));
}

ViewBounds grain_bounds(const FrameData& f) {
  ViewBounds b;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (is_finite(f.position[i]) && i < f.radius.size()) b.add(f.position[i], f.radius[i]);
  }
  return b;
}

ViewBounds grain_core_bounds(const FrameData& f) {
  if (f.size() < 1000) return grain_bounds(f);
  std::vector<Real> c[3];
  Real r_max = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    const Vec3& p = f.position[i];
    if (!is_finite(p)) continue;
    c[0].push_back(p.x), c[1].push_back(p.y), c[2].push_back(p.z);
    r_max = std::max(r_max, f.radius[i]);
  }
  if (c[0].empty()) return {};
  Real lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const auto n = c[a].size();
    const auto k_lo = n / 200, k_hi = n - 1 - n / 200;
    std::nth_element(c[a].begin(), c[a].begin() + static_cast<std::ptrdiff_t>(k_lo), c[a].end());
    lo[a] = c[a][k_lo];
    std::nth_element(c[a].begin(), c[a].begin() + static_cast<std::ptrdiff_t>(k_hi), c[a].end());
    hi[a] = c[a][k_hi];
  }
  ViewBounds b;
  b.add({lo[0], lo[1], lo[2]}, r_max);
  b.add({hi[0], hi[1], hi[2]}, r_max);
  return b;
}

namespace {

// The corners of the box [lo, hi] in a shape's own frame, rotated and moved as drawn.
void add_local_box(ViewBounds& b, const GeometryConfig& g, const Vec3& lo, const Vec3& hi) {
  const Mat3 m = rotation_xyz_deg(g.rotation_deg);
  for (int k = 0; k < 8; ++k)
    b.add(g.center + m * Vec3{k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z}, 0);
}

}  // namespace

ViewBounds geometry_bounds(const std::vector<GeometryConfig>& geometry,
                           const std::vector<const TriangleMesh*>& meshes) {
  ViewBounds b;
  for (std::size_t k = 0; k < geometry.size(); ++k) {
    const GeometryConfig& g = geometry[k];
    if (g.render == RenderStyle::Hidden) continue;
    switch (g.type) {
      case GeometryType::Mesh:
        if (k < meshes.size() && meshes[k])
          for (const Vec3& v : meshes[k]->vertices) b.add(v, 0);
        break;
      case GeometryType::Plane:
        break;  // infinite: not framed
      case GeometryType::Sphere:
        b.add(g.center, g.radius);
        break;
      case GeometryType::Box: {
        const double t = g.container ? g.wall_thickness : 0;
        const Vec3 h = g.size * 0.5 + Vec3{t, t, t};
        add_local_box(b, g, -h, h);
        break;
      }
      case GeometryType::Cylinder: {
        const double t = g.container ? g.wall_thickness : 0;
        const double r = g.radius + t, hz = 0.5 * g.height + t;
        add_local_box(b, g, {-r, -r, -hz}, {r, r, hz});
        break;
      }
      case GeometryType::Bowl: {
        // the shell below its rim plane
        const double r = g.radius + g.wall_thickness;
        add_local_box(b, g, {-r, -r, -r}, {r, r, g.depth.value_or(g.radius) - g.radius});
        break;
      }
      case GeometryType::Heightmap:
        if (!g.heights.z.empty()) {
          const auto [lo, hi] = std::minmax_element(g.heights.z.begin(), g.heights.z.end());
          b.add({g.extent[0], g.extent[1], *lo - g.base_thickness}, 0);
          b.add({g.extent[2], g.extent[3], *hi}, 0);
        }
        break;
    }
  }
  return b;
}

// Looks at the box from a 3/4 elevated direction, just far enough for its eight corners to fit
// the field of view with a 10 % border, and re-aimed at the middle of what the picture shows
// (the box's centre leaves the empty corners above a heap on screen). Every sphere inside the box
// projects inside the corners' hull, so the corners alone decide the framing.
std::pair<Vec3, Vec3> auto_camera(const ViewBounds& bounds, const PovOptions& opt) {
  ViewBounds b = bounds;
  if (b.empty) b.add({0, 0, 0}, 0.5);
  std::array<Vec3, 8> corners;
  for (int k = 0; k < 8; ++k)
    corners[k] = {k & 1 ? b.hi.x : b.lo.x, k & 2 ? b.hi.y : b.lo.y, k & 4 ? b.hi.z : b.lo.z};
  // from the target towards the camera: 35 degrees up, so that it sees into a bowl or a box
  const Vec3 view = normalized({1.0, -1.4, 1.2});
  const Vec3 fwd = -view;
  const Vec3 right = normalized(cross(fwd, {0, 0, 1}));
  const Vec3 up = cross(right, fwd);
  const double aspect = static_cast<double>(opt.width) / std::max(opt.height, 1);
  const double tan_h = 0.9 * std::tan(deg_to_rad(std::clamp(opt.fov_deg, 1.0, 170.0)) / 2);
  const double tan_v = tan_h / aspect;
  Vec3 target = b.centre();
  double dist = 0;
  for (int pass = 0; pass < 3; ++pass) {
    // Distance: a corner at depth dist + p.fwd must be within tan_h of the axis (and up, tan_v).
    dist = 1.05 * b.radius();  // at least outside the bounds
    for (const Vec3& c : corners) {
      const Vec3 p = c - target;
      dist = std::max(dist, std::abs(dot(p, right)) / tan_h - dot(p, fwd));
      dist = std::max(dist, std::abs(dot(p, up)) / tan_v - dot(p, fwd));
    }
    if (pass == 2) break;
    // Re-aim at the middle of the corners' extent on screen.
    double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
    for (const Vec3& c : corners) {
      const Vec3 p = c - target;
      const double depth = std::max(dist + dot(p, fwd), 1e-9 * dist);
      const double u = dot(p, right) / depth, v = dot(p, up) / depth;
      u0 = std::min(u0, u);
      u1 = std::max(u1, u);
      v0 = std::min(v0, v);
      v1 = std::max(v1, v);
    }
    target += right * (0.5 * (u0 + u1) * dist) + up * (0.5 * (v0 + v1) * dist);
  }
  return {target + view * dist, target};
}

namespace {

// The static layer as one smooth mesh2 (normals from the heights around each vertex) in a sand
// texture whose grain is the grains' size: seen between the visible grains, it reads as the
// packed sand under them rather than as a floor showing through.
void write_static_layer(std::string& s, const SandSurface& sf) {
  const int nx = sf.nx, ny = sf.ny;
  const auto at = [&](int i, int j) { return static_cast<std::size_t>(j) * nx + i; };
  if (sf.empty() || sf.z.size() != at(0, ny) || sf.sand.size() != sf.z.size()) return;
  std::vector<std::array<int, 3>> faces;
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      if (!(sf.sand[at(i, j)] | sf.sand[at(i + 1, j)] | sf.sand[at(i, j + 1)] |
            sf.sand[at(i + 1, j + 1)]))
        continue;
      const int a = static_cast<int>(at(i, j)), b = a + 1, c = a + nx, d = c + 1;
      faces.push_back({a, b, d});
      faces.push_back({a, d, c});
    }
  if (faces.empty()) return;
  // Sand does not climb what stands beside it: a column without sand next to sand (a wall, a
  // shelf, an obstacle) is drawn no higher than the highest sand around it, so the surface's edge
  // runs into the solid there rather than up its face.
  std::vector<Real> z = sf.z;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (sf.sand[at(i, j)]) continue;
      Real top = -std::numeric_limits<Real>::infinity();
      for (int b = std::max(j - 1, 0); b <= std::min(j + 1, ny - 1); ++b)
        for (int a = std::max(i - 1, 0); a <= std::min(i + 1, nx - 1); ++a)
          if (sf.sand[at(a, b)]) top = std::max(top, sf.z[at(a, b)]);
      if (top > -std::numeric_limits<Real>::infinity()) z[at(i, j)] = std::min(z[at(i, j)], top);
    }
  const Real grain = sf.grain_diameter > 0 ? sf.grain_diameter : sf.cell;
  const Vec3 lo = sand_srgb(0), hi = sand_srgb(kSandShades - 1);
  line(s,
       "// the static layer: h, the top of the sand that does not move (its grains are not "
       "drawn)");
  line(s, "#declare StaticSand = texture { pigment { granite color_map { [0 srgb ", lo * 0.92,
       "] [0.5 srgb ", (lo + hi) * 0.5, "] [1 srgb ", hi, "] } scale ", 2 * grain,
       " } normal { bumps 0.5 scale ", 0.4 * grain, " } finish { SandFinish } }");
  line(s, "mesh2 {");
  line(s, "  vertex_vectors { ", sf.z.size(), ",");
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      line(s, "    <", sf.origin_x + (i + 0.5) * sf.cell, ",", sf.origin_y + (j + 0.5) * sf.cell,
           ",", z[at(i, j)], ">");
  line(s, "  }");
  line(s, "  normal_vectors { ", sf.z.size(), ",");
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int i0 = std::max(i - 1, 0), i1 = std::min(i + 1, nx - 1);
      const int j0 = std::max(j - 1, 0), j1 = std::min(j + 1, ny - 1);
      const Real gx = (z[at(i1, j)] - z[at(i0, j)]) / ((i1 - i0) * sf.cell);
      const Real gy = (z[at(i, j1)] - z[at(i, j0)]) / ((j1 - j0) * sf.cell);
      line(s, "    ", normalized(Vec3{-gx, -gy, 1}));
    }
  line(s, "  }");
  line(s, "  face_indices { ", faces.size(), ",");
  for (const auto& f : faces) line(s, "    <", f[0], ",", f[1], ",", f[2], ">");
  line(s, "  }");
  line(s, "  texture { StaticSand }");
  line(s, "}");
}

}  // namespace

void write_pov_scene(const std::string& path, const FrameData& f,
                     const std::vector<GeometryConfig>& geometry, const PovOptions& opt,
                     const std::vector<const TriangleMesh*>& meshes,
                     const SandSurface* static_layer) {
  write_file_atomic(path, pov_scene_text(f, geometry, opt, meshes, static_layer), Sync::Later);
}

std::string pov_scene_text(const FrameData& f, const std::vector<GeometryConfig>& geometry,
                           const PovOptions& opt, const std::vector<const TriangleMesh*>& meshes,
                           const SandSurface* static_layer) {
  if (f.radius.size() != f.size() || (!f.id.empty() && f.id.size() != f.size())) {
    throw std::invalid_argument("pov_scene_text: FrameData arrays have different lengths");
  }
  const ViewBounds b = scene_bounds(f, geometry, meshes, opt);
  Camera cam{opt.camera_position, opt.camera_look_at, opt.camera_up};
  if (opt.auto_camera) {
    const auto [location, look_at] = auto_camera(b, opt);
    cam = {location, look_at, {0, 0, 1}};
  }
  std::string s;
  s.reserve(2048 + 48 * f.size());
  write_header(s, cam, b, opt, f.size());
  line(s, fmt::format("#ifndef (SandflowTime) #declare SandflowTime = {}; #end", opt.time));
  for (std::size_t k = 0; k < geometry.size(); ++k) {
    const GeometryConfig& g = geometry[k];
    // a removed solid is drawn up to the frame whose steps it still acted in (its time, to the
    // step's rounding)
    if (g.remove_at)
      line(s, fmt::format("#if (SandflowTime <= {})  // remove_at",
                          *g.remove_at * (1 + 1e-9) + 1e-12));
    write_geometry(s, g, b, k < meshes.size() ? meshes[k] : nullptr);
    if (g.remove_at) line(s, "#end");
  }
  // below everything drawn, by a hair so that it does not touch a flat bottom; not when the
  // camera is under it (it would hide everything)
  const double floor_z = b.lo.z - 1e-3 * b.radius();
  if (opt.floor && !has_visible_plane(geometry) && cam.location.z > floor_z) {
    line(s, "// floor (the scene has no plane): for looks only");
    line(s, "plane { z, ", floor_z, " texture { Floor } }");
  }
  line(s, "");
  if (static_layer) write_static_layer(s, *static_layer);
  write_grains(s, f);
  return s;
}

std::string find_povray() {
  return find_program("povray");
}

namespace {

// Less free than this after a program failed, the disk is full: what filled it was the file the
// program was writing (a disk that has this much left is not what stopped it).
constexpr std::uintmax_t kNearlyFullDisk = 1u << 20;

std::string byte_size(std::uintmax_t bytes) {
  return bytes < 1'000'000 ? fmt::format("{} kB", bytes / 1000)
                           : fmt::format("{:.3g} MB", static_cast<double>(bytes) / 1e6);
}

bool ascii_without_spaces(const std::string& name) {
  return std::all_of(name.begin(), name.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return u > 0x20 && u < 0x7f;
  });
}

// Runs `args` with run_logged (core/process.hpp) into the file `partial`, which becomes
// `out_path` only when the program succeeded and `whole` (io/media_check.hpp) finds nothing wrong
// with what it wrote: no half-made picture or movie is ever left under its name, whatever the
// program's exit status says. Throws OutputError with the end of the log, and what the disk
// holds when it is full (the log, on the same disk, may be cut before it says so).
void run_into_file(const std::vector<std::string>& args, const std::string& work_dir,
                   const std::string& log_path, const std::string& what, const std::string& partial,
                   const std::string& out_path,
                   const std::function<std::string(const std::string&)>& whole,
                   std::int64_t* peak_bytes = nullptr) {
  std::error_code ec;
  std::string problem = run_logged(args, work_dir, log_path, what, peak_bytes);
  if (problem.empty()) {
    if (!fs::exists(partial, ec))
      problem = what + " wrote nothing";
    else if (const std::string wrong = whole(partial); !wrong.empty())
      problem = what + " ended as if done, but what it wrote is not whole: " + wrong;
  }
  if (!problem.empty()) {
    // measured before the unfinished file is removed: it is what filled the disk
    const fs::path folder = fs::path(out_path).parent_path();
    const fs::space_info space = fs::space(folder.empty() ? fs::path(".") : folder, ec);
    if (!ec && space.available < kNearlyFullDisk)
      problem += fmt::format("; the disk holding {} is full ({} free): make room, then try again",
                             fs::absolute(folder, ec).string(), byte_size(space.available));
    fs::remove(partial, ec);
    throw OutputError(out_path + ": " + problem + "; end of " + log_path + ":\n" +
                      tail_of(log_path, 1500));
  }
  fs::rename(partial, out_path, ec);
  if (ec) {
    const std::string reason = ec.message();
    fs::remove(partial, ec);
    throw OutputError(out_path + ": cannot rename " + partial + " to it: " + reason);
  }
}

}  // namespace

std::int64_t render_pov(const std::string& pov_path, const std::string& png_path, int width,
                        int height, int threads, bool antialias) {
  const std::string exe = find_povray();
  if (exe.empty()) {
    throw OutputError(png_path +
                      ": cannot render: povray is not on PATH (sudo apt-get install povray)");
  }
  std::error_code ec;
  const fs::path pov_abs = fs::absolute(pov_path, ec);
  const std::string log_path = fs::absolute(png_path + ".log", ec).string();
  // POV-Ray writes to a temporary name; the PNG appears only when the render succeeded.
  const std::string partial = fs::absolute(png_path + ".partial.png", ec).string();
  fs::remove(partial, ec);

  // POV-Ray splits its options at spaces and cannot open non-ASCII paths: it runs in the scene's
  // folder (its default I/O policy allows that folder) and is given names relative to it, which
  // sandflow makes ASCII (frame numbers); the folder's own name never reaches it
  const fs::path work_dir = pov_abs.parent_path();
  const fs::path partial_rel = fs::path(partial).lexically_relative(work_dir);
  if (partial_rel.empty() || !ascii_without_spaces(partial_rel.string()) ||
      !ascii_without_spaces(pov_abs.filename().string()))
    throw OutputError(png_path + ": cannot render: POV-Ray cannot be given the name " +
                      partial_rel.string() + " or " + pov_abs.filename().string() +
                      " (spaces or non-ASCII characters); write the picture beside the scene file");
  std::vector<std::string> args = {exe,
                                   "+I" + pov_abs.filename().string(),
                                   "+O" + partial_rel.string(),
                                   "+W" + std::to_string(width),
                                   "+H" + std::to_string(height),
                                   antialias ? "+A0.3" : "-A",
                                   "+FN",
                                   "-D",
                                   "-P",
                                   "Output_Alpha=off"};
  if (threads > 0) args.push_back("+WT" + std::to_string(threads));
  try {
    std::int64_t peak = 0;
    run_into_file(args, work_dir.string(), log_path, "povray", partial, png_path, png_problem,
                  &peak);
    return peak;
  } catch (const OutputError&) {
    // POV-Ray's record of a render that did not end (NAME.partial.pov-state)
    fs::remove(fs::path(partial).replace_extension(".pov-state"), ec);
    // That record grows to about 20 bytes a pixel while POV-Ray renders (measured with POV-Ray
    // 3.7, which cannot be told not to write it): on a full disk POV-Ray stops with status 1 and
    // a log cut short, saying nothing of the disk, so sandflow says it.
    const std::uintmax_t need = static_cast<std::uintmax_t>(width) * height * 24 + (1u << 20);
    const fs::space_info space = fs::space(work_dir, ec);
    if (!ec && space.available < need)
      throw OutputError(fmt::format(
          "{}: cannot render: the disk holding {} has {} free, and POV-Ray needs about {} for a "
          "picture of {} x {} while it renders (its state file): make room, then render again "
          "(POV-Ray's log: {})",
          png_path, work_dir.string(), byte_size(space.available), byte_size(need), width, height,
          log_path));
    throw;
  }
}

void encode_movie(const std::vector<std::string>& folders, int first, int count, double fps,
                  const std::string& mp4_path) {
  const std::string exe = find_program("ffmpeg");
  if (exe.empty())
    throw OutputError(mp4_path +
                      ": cannot encode: ffmpeg is not on PATH (sudo apt-get install "
                      "ffmpeg)");
  if (folders.empty() || count < 1)
    throw std::invalid_argument("encode_movie: no folder or no frame to encode");
  std::error_code ec;
  const std::string log_path = fs::absolute(mp4_path + ".log", ec).string();
  const std::string partial = fs::absolute(mp4_path + ".partial", ec).string();
  fs::remove(partial, ec);
  char rate[32];
  std::snprintf(rate, sizeof rate, "%.9g", fps);
  std::vector<std::string> args = {exe, "-nostdin", "-y", "-hide_banner"};
  for (const std::string& folder : folders) {
    // ffmpeg reads '%' in an image path as the start of its pattern: a literal one is "%%"
    std::string pattern;
    for (char ch : fs::absolute(folder, ec).string())
      pattern += ch == '%' ? "%%" : std::string(1, ch);
    pattern += "/%04d.png";
    for (const std::string& a :
         {std::string("-framerate"), std::string(rate), std::string("-start_number"),
          std::to_string(first), std::string("-i"), pattern})
      args.push_back(a);
  }
  // side by side when there are several; yuv420p (what players expect) needs even sizes: pad by
  // a pixel when odd
  std::string filter;
  if (folders.size() > 1) {
    for (std::size_t k = 0; k < folders.size(); ++k) filter += "[" + std::to_string(k) + ":v]";
    filter += "hstack=inputs=" + std::to_string(folders.size()) + ",";
  }
  filter += "pad=ceil(iw/2)*2:ceil(ih/2)*2";
  for (const std::string& a :
       {std::string("-frames:v"), std::to_string(count),
        std::string(folders.size() > 1 ? "-filter_complex" : "-vf"), filter, std::string("-c:v"),
        std::string("libx264"), std::string("-pix_fmt"), std::string("yuv420p"),
        std::string("-movflags"), std::string("+faststart"), std::string("-f"), std::string("mp4"),
        partial})
    args.push_back(a);
  run_into_file(args, fs::absolute(folders.front(), ec).string(), log_path, "ffmpeg", partial,
                mp4_path, [count](const std::string& movie) { return mp4_problem(movie, count); });
}

std::string pov_grain_lines(const FrameData& f) {
  if (f.radius.size() != f.size() || (!f.id.empty() && f.id.size() != f.size()))
    throw std::invalid_argument("pov_grain_lines: FrameData arrays have different lengths");
  std::string s;
  s.reserve(48 * f.size() + 64);
  write_grains(s, f);
  return s;
}

}  // namespace sandflow

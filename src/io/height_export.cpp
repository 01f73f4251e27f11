#include "io/height_export.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <limits>

#include <fmt/format.h>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/read_file.hpp"
#include "io/export_formats.hpp"
#include "io/png_gray.hpp"

namespace sandflow {

namespace {

void check_size(const HeightFieldParams& grid, const std::vector<Real>& z, const char* who) {
  if (grid.nx < 1 || grid.ny < 1 ||
      z.size() != static_cast<std::size_t>(grid.nx) * static_cast<std::size_t>(grid.ny))
    throw std::invalid_argument(std::string(who) + ": the heights do not match the grid");
}

}  // namespace

std::size_t write_height_png(const std::string& path, const HeightFieldParams& grid,
                             const std::vector<Real>& z, const HeightRange& range) {
  check_size(grid, z, "write_height_png");
  const int nx = grid.nx, ny = grid.ny;
  std::vector<double> value(z.size());
  std::size_t clamped = 0;
  for (int row = 0; row < ny; ++row) {
    const int j = ny - 1 - row;  // row 0: the highest y
    for (int i = 0; i < nx; ++i) {
      const Real h = z[static_cast<std::size_t>(j) * nx + i];
      double v = std::isfinite(h) ? (h - range.z_min) / (range.z_max - range.z_min) : 0.0;
      if (!(v >= 0.0 && v <= 1.0)) {
        ++clamped;
        v = std::clamp(std::isfinite(v) ? v : 0.0, 0.0, 1.0);
      }
      value[static_cast<std::size_t>(row) * nx + i] = v;
    }
  }
  write_file_atomic_by_name(
      path, [&](const std::string& tmp) { write_gray_png(tmp, nx, ny, value, 16); }, Sync::Later);
  return clamped;
}

void write_height_obj(const std::string& path, const HeightFieldParams& grid,
                      const std::vector<Real>& z, UpAxis up, const std::string& comment) {
  check_size(grid, z, "write_height_obj");
  const int nx = grid.nx, ny = grid.ny;
  std::string s;
  s.reserve(64 + 40 * z.size() + 2 * 30 * z.size());
  fmt::format_to(std::back_inserter(s), "# {}\n# {} x {} columns of {} m, up axis {}\n",
                 comment.substr(0, comment.find('\n')), nx, ny, grid.cell, up_axis_name(up));
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const Real h = z[static_cast<std::size_t>(j) * nx + i];
      const Vec3 c{grid.x0 + (i + 0.5) * grid.cell, grid.y0 + (j + 0.5) * grid.cell,
                   std::isfinite(h) ? h : 0.0};
      const Vec3 v = to_up_axis(c, up);
      fmt::format_to(std::back_inserter(s), "v {:.7g} {:.7g} {:.7g}\n", v.x, v.y, v.z);
    }
  // a rotation keeps the winding, so the normals point up in either frame
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const long k = 1L + static_cast<long>(j) * nx + i;
      fmt::format_to(std::back_inserter(s), "f {} {} {}\nf {} {} {}\n", k, k + 1, k + nx + 1, k,
                     k + nx + 1, k + nx);
    }
  write_file_atomic(path, s);
}

nlohmann::json height_sidecar(const HeightFieldParams& grid, const HeightRange& range, UpAxis up) {
  const Real c = grid.cell;
  return {
      {"nx", grid.nx},
      {"ny", grid.ny},
      {"cell_size", c},
      {"origin", {grid.x0, grid.y0}},
      {"extent",
       {grid.x0 + 0.5 * c, grid.y0 + 0.5 * c, grid.x0 + (grid.nx - 0.5) * c,
        grid.y0 + (grid.ny - 0.5) * c}},
      {"png",
       {{"bit_depth", 16},
        {"z_min", range.z_min},
        {"z_max", range.z_max},
        {"metres_per_level", range.step()},
        {"height", "z = z_min + grey / 65535 * (z_max - z_min)"},
        {"rows", "row 0 holds the columns of highest y; column 0 those of lowest x"}}},
      {"obj", {{"up_axis", std::string(up_axis_name(up))}}},
      {"files",
       {{"H_NNNN", "H, the top of the sand (the terrain where there is none)"},
        {"h_NNNN", "h, the top of the static layer"}}},
      {"units", "metres, scene frame (z up) for origin, extent and the z range"},
  };
}

std::optional<HeightImages> read_height_images(const std::string& run) {
  namespace fs = std::filesystem;
  const std::optional<std::string> text =
      read_file_if_present((fs::path(run) / "heightfield" / "heightfield.json").string(),
                           "height field's record", kAnyFileSize);
  if (!text) return std::nullopt;
  const auto j = nlohmann::json::parse(*text, nullptr, false);
  try {
    HeightImages h;
    h.origin_x = j.at("origin").at(0).get<Real>();
    h.origin_y = j.at("origin").at(1).get<Real>();
    h.cell = j.at("cell_size").get<Real>();
    h.nx = j.at("nx").get<int>();
    h.ny = j.at("ny").get<int>();
    h.z_min = j.at("png").at("z_min").get<Real>();
    h.z_max = j.at("png").at("z_max").get<Real>();
    if (h.nx < 2 || h.ny < 2 || !(h.cell > 0) || !(h.z_max > h.z_min)) return std::nullopt;
    return h;
  } catch (const nlohmann::json::exception&) {
    return std::nullopt;  // not a height field this build wrote
  }
}

std::vector<Real> read_height_frame(const std::string& run, const char* name, int frame,
                                    const HeightImages& grid) {
  namespace fs = std::filesystem;
  const fs::path png = fs::path(run) / "heightfield" / fmt::format("{}_{:04d}.png", name, frame);
  std::error_code ec;
  if (!fs::exists(png, ec)) return {};
  const GrayImage img = read_gray_png(png.string(), std::max(grid.nx, grid.ny));
  if (img.width != grid.nx || img.height != grid.ny)
    throw InputError(fmt::format("{}: {} x {} pixels, but heightfield.json says {} x {}",
                                 png.string(), img.width, img.height, grid.nx, grid.ny));
  std::vector<Real> z(static_cast<std::size_t>(grid.nx) * grid.ny);
  for (int j = 0; j < grid.ny; ++j)
    for (int i = 0; i < grid.nx; ++i)  // (image row 0 holds the columns of highest y)
      z[static_cast<std::size_t>(j) * grid.nx + i] =
          grid.z_min + img.value[static_cast<std::size_t>(grid.ny - 1 - j) * grid.nx + i] *
                           (grid.z_max - grid.z_min);
  return z;
}

std::vector<std::uint8_t> static_sand_columns(const std::vector<Real>& h, const HeightImages& grid,
                                              const Geometry& solids, Real d,
                                              std::vector<Real>* ground) {
  std::vector<std::uint8_t> sand(h.size(), 0);
  if (ground) ground->assign(h.size(), -std::numeric_limits<Real>::infinity());
  for (std::size_t k = 0; k < h.size(); ++k) {
    const Real z_from = h[k] + 0.1 * d;
    Real top = -std::numeric_limits<Real>::infinity();
    for (const auto& [bottom, t] :
         solids.solid_intervals(grid.x_of(k), grid.y_of(k), z_from, h[k] - 1e3))
      top = std::max(top, std::min(t, z_from));
    sand[k] = h[k] > top + 0.25 * d;
    if (ground) (*ground)[k] = top;
  }
  return sand;
}

}  // namespace sandflow

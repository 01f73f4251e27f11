// The readers of the tables a scene has at most once: [material], [simulation], [stiffness],
// [surface], [output] and [camera] (scene_tables.hpp).

#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "core/threads.hpp"
#include "dem/contact.hpp"
#include "io/export_formats.hpp"
#include "scene/scene_tables.hpp"
#include "surface/surface_params.hpp"

namespace sandflow::loader {
namespace {

constexpr Choices<Mode> kModes[] = {{"surface", Mode::Surface}, {"dem", Mode::Dem}};
constexpr Choices<OnLeave> kOnLeave[] = {{"stop", OnLeave::Stop}, {"count", OnLeave::Count}};
constexpr Choices<UpAxis> kUpAxes[] = {{"z", UpAxis::Z}, {"y", UpAxis::Y}};

}  // namespace

void read_material(TableReader r, MaterialConfig& m) {
  r.read("density", m.density, kPositive);
  r.read("diameter", m.diameter, kPositive);
  r.read("diameter_spread", m.diameter_spread, closed(0, 0.5));
  r.read("k_n", m.k_n, kPositive);
  r.read("k_t_ratio", m.k_t_ratio, closed(0, 1));
  r.read("restitution", m.restitution, open_closed(0, 1));
  if (m.restitution < smallest_restitution())
    r.fail_at(
        "restitution",
        fmt::format("{} = {:.3g} is below {:.3g}, the least a grain of this contact law keeps "
                    "of its speed (its dashpot at the strongest damping it is given); use a "
                    "value at least that",
                    r.name("restitution"), m.restitution, smallest_restitution()));
  r.read("tangential_damping_ratio", m.tangential_damping_ratio, closed(0, 1));
  r.read("friction", m.friction, kNonNegative);
  r.read("rolling_friction", m.rolling_friction, kNonNegative);
  r.read("rolling_stiffness_ratio", m.rolling_stiffness_ratio, kNonNegative);
  r.read("rolling_damping_ratio", m.rolling_damping_ratio, kNonNegative);
  r.read("twisting_friction", m.twisting_friction, kNonNegative);
  r.read("wall_friction", m.wall_friction, kNonNegative);
  r.read("wall_rolling_friction", m.wall_rolling_friction, kNonNegative);
  r.read("wall_twisting_friction", m.wall_twisting_friction, kNonNegative);
  r.finish("[material]");
}

void read_simulation(TableReader r, SimulationConfig& s) {
  r.read("mode", s.mode, kModes);
  r.read("gravity", s.gravity);
  r.read("dt", s.dt, kPositive);
  r.read("dt_fraction", s.dt_fraction, open_closed(0, 0.2));
  if (r.has("dt_fraction") && r.in_file("dt"))
    r.warn_at("dt_fraction", r.name("dt_fraction") + " is not used: " + r.name("dt") + " is given");
  r.read("skin", s.skin, open_closed(0, 2));
  r.read("skin_steps", s.skin_steps, closed(0, 1000));  // 0: one skin for all grains
  r.read("skin_max", s.skin_max, closed(0, 2));
  r.read("sort_every", s.sort_every, kNonNegative);  // 0: never re-sort
  r.read("seed", s.seed, kNonNegative);
  r.read("threads", s.threads, closed(0, kMaxThreads));
  r.read("max_overlap_stop", s.max_overlap_stop, open_closed(0, 1));
  r.read("domain", s.domain);
  r.read("on_leave", s.on_leave, kOnLeave);
  r.finish("[simulation]");
  if (s.domain) {
    const auto& d = *s.domain;
    if (!(d[3] > d[0]) || !(d[4] > d[1]) || !(d[5] > d[2]))
      r.fail_at("domain",
                r.name("domain") + " = [" + format_real(d[0]) + ", " + format_real(d[1]) + ", " +
                    format_real(d[2]) + ", " + format_real(d[3]) + ", " + format_real(d[4]) + ", " +
                    format_real(d[5]) +
                    "]: expected [x0, y0, z0, x1, y1, z1] with x1 > x0, y1 > y0, z1 > z0");
  }
}

void read_stiffness(TableReader r, StiffnessConfig& k) {
  r.read("from_load", k.from_load);
  r.read("max_overlap", k.max_overlap, open_closed(0, 0.5));
  r.read("impact_overlap", k.impact_overlap, open_closed(0, 0.5));
  r.read("impact_speed", k.impact_speed, kNonNegative);
  r.read("dem_depth", k.dem_depth, kPositive);
  r.read("surface_depth", k.surface_depth, kPositive);
  r.finish("[stiffness]");
  // (impact_overlap stays the limit compare and table1 hold the overlaps to; a --set of
  // from_load, as compare --equal-stiffness makes, leaves the file's keys unused knowingly)
  if (!k.from_load && r.in_file("from_load"))
    for (const std::string_view key : {"max_overlap", "impact_speed", "dem_depth", "surface_depth"})
      if (r.has(key))
        r.warn_at(key, r.name(key) + " is not used: " + r.name("from_load") +
                           " = false takes k_n from material.k_n");
}

namespace {

// Angles in scene files are degrees. One small enough to be the key's range in radians (below
// `most` = pi / 2 for an angle of repose, pi for a field of view) reads like radians; it is taken
// as given (it is in range), with a warning that says what it would be in degrees.
void warn_if_radians(const TableReader& r, std::string_view key, Real deg, Real most,
                     std::string_view looks) {
  if (deg < most)
    r.warn_at(key, r.name(key) + " = " + format_real(deg) + " is in degrees, " +
                       std::string(looks) + "; if it was meant in radians, write " +
                       fmt::format("{:.4g}", rad_to_deg(deg)));
}

}  // namespace

void check_extent(const TableReader& r, const std::array<Real, 4>& extent) {
  const auto& [x0, y0, x1, y1] = extent;
  if (!(x1 > x0) || !(y1 > y0))
    r.fail_at("extent", r.name("extent") + " = [" + format_real(x0) + ", " + format_real(y0) +
                            ", " + format_real(x1) + ", " + format_real(y1) +
                            "]: expected [x0, y0, x1, y1] with x1 > x0 and y1 > y0");
}

namespace {

// The height field's extent: a rectangle, and the grid it makes at the cell size refused here,
// with its place, when too large (without an extent, surface_params() refuses it once the
// geometry gives the domain).
void check_surface_extent(const TableReader& r, const SurfaceConfig& s, Real diameter) {
  check_extent(r, *s.extent);
  const auto& [x0, y0, x1, y1] = *s.extent;
  const Real cell = s.cell_size.value_or(diameter);
  const Real nx = std::ceil((x1 - x0) / cell), ny = std::ceil((y1 - y0) / cell);
  if (!(nx * ny <= static_cast<Real>(kMaxHeightFieldColumns)))
    r.fail_at(s.cell_size ? "cell_size" : "extent",
              r.name("extent") + " at " +
                  (s.cell_size ? r.name("cell_size") + " = " + format_real(cell) + " m"
                               : "a cell size of " + format_real(cell) +
                                     " m (the grain diameter: cell_size unset)") +
                  " makes a height field of " + format_count(nx) + " x " + format_count(ny) +
                  " columns, more than the limit of " + std::to_string(kMaxHeightFieldColumns) +
                  ": set a larger cell_size or a smaller extent");
}

}  // namespace

void read_surface(TableReader r, SurfaceConfig& s, Real diameter) {
  r.read("cell_size", s.cell_size, kPositive);
  r.read("exchange_rate", s.exchange_rate, kPositive);
  std::optional<Real> repose_deg;
  std::optional<Real> max_deg;
  r.read("repose_angle", repose_deg, open(0, 90));
  r.read("max_angle", max_deg, open(0, 90));
  r.read("rolling_min", s.rolling_min, kNonNegative);
  r.read("flowing_min", s.flowing_min, kNonNegative);
  r.read("flowing_hold", s.flowing_hold, kNonNegative);
  r.read("erosion_reach", s.erosion_reach, kNonNegative);
  r.read("close_after", s.close_after, kNonNegative);
  r.read("blows", s.blows);
  r.read("interface_thickness", s.interface_thickness, kPositive);
  r.read("update_interval", s.update_interval, kPositive);
  r.read("trap_speed", s.trap_speed, kNonNegative);
  r.read("flow_speed", s.flow_speed, kNonNegative);
  r.read("extent", s.extent);
  r.finish("[surface]");

  for (const auto& [key, deg] : {std::pair{"repose_angle", repose_deg}, {"max_angle", max_deg}})
    if (deg) warn_if_radians(r, key, *deg, kPi / 2, "a heap all but flat");
  if (repose_deg) {
    s.repose_angle = deg_to_rad(*repose_deg);
    s.repose_angle_given = true;
  }
  if (max_deg) {
    s.max_angle = deg_to_rad(*max_deg);
    if (*s.max_angle < s.repose_angle) {
      // The default repose angle is printed in degrees, rounded off its round trip via radians.
      const std::string repose_text =
          repose_deg
              ? format_real(*repose_deg)
              : format_real(std::round(rad_to_deg(s.repose_angle) * 1e9) / 1e9) + " (the default)";
      r.fail_at("max_angle", r.name("max_angle") + " = " + format_real(*max_deg) +
                                 " is less than " + r.name("repose_angle") + " = " + repose_text +
                                 " (degrees): expected max_angle >= repose_angle");
    }
  }
  if (s.extent) check_surface_extent(r, s, diameter);
}

void read_output(TableReader r, OutputConfig& o, const MaterialConfig& m) {
  r.read("fps", o.fps, kPositive);
  r.read("duration", o.duration, kPositive);
  r.read("settle_time", o.settle_time, kNonNegative);
  std::optional<std::vector<TableReader::Word>> exports;
  r.read("export", exports);
  r.read("up_axis", o.up_axis, kUpAxes);
  r.read("vdb_voxel_size", o.vdb_voxel_size, kPositive);
  if (o.vdb_voxel_size && *o.vdb_voxel_size < m.largest_diameter() / kVdbGrainVoxelsMax)
    r.fail_at("vdb_voxel_size",
              fmt::format("{} = {:.3g} m is below {:.3g} m, the largest grain's diameter / {:.0f}: "
                          "a finer voxel draws nothing a picture can show, at a cost in bytes that "
                          "grows as 1 / voxel^2",
                          r.name("vdb_voxel_size"), *o.vdb_voxel_size,
                          m.largest_diameter() / kVdbGrainVoxelsMax, kVdbGrainVoxelsMax));
  r.finish("[output]");
  if (exports) {
    o.exports.emplace();
    for (const auto& w : *exports) {
      const auto f = export_format(w.text);
      if (!f)
        fail(w.place, w.name + " = " + in_quotes(w.text) + " is not an export: expected one of " +
                          export_names() + " (an empty array [] writes no per-frame files)");
      if (!has_export(*o.exports, *f)) o.exports->push_back(*f);
    }
  }
}

// The render camera: a fixed one (position and look_at together, up optional) or only a field of
// view for the automatic one.
void read_camera(TableReader r, CameraConfig& c) {
  const auto vector = [&r](std::string_view key, std::optional<Vec3>& out) {
    const bool present = r.has(key);
    Vec3 v{0, 0, 0};
    r.read(key, v);  // also makes `key` one the table accepts
    if (present) out = v;
  };
  vector("position", c.position);
  vector("look_at", c.look_at);
  vector("up", c.up);
  r.read("fov", c.fov_deg, open(0, 180));
  if (r.has("fov")) warn_if_radians(r, "fov", c.fov_deg, kPi, "a view through a keyhole");
  r.finish("[camera]");

  if (c.position && !c.look_at)
    r.require("look_at", "[x, y, z], the point the camera at camera.position looks at");
  if (c.look_at && !c.position)
    r.require("position", "[x, y, z], where the camera looking at camera.look_at stands");
  if (c.up && !c.position)
    r.fail_at("up", r.name("up") +
                        " is set without camera.position and camera.look_at: the automatic camera "
                        "keeps z up; set all three or leave up out");
  if (!c.position) return;
  const Vec3 view = *c.look_at - *c.position;
  if (norm(view) == 0)
    r.fail_at("look_at", r.name("look_at") +
                             " is camera.position: expected a point the camera "
                             "looks at, away from where it stands");
  // (past about 1e154 m the length overflows, and every direction below would be NaN)
  if (!std::isfinite(norm(view)))
    r.fail_at("look_at", r.name("look_at") +
                             " is too far from camera.position: the distance between them is not "
                             "a finite number");
  if (c.up) {
    const Real n = norm(*c.up);
    if (n == 0) r.fail_at("up", r.name("up") + " = [0, 0, 0]: expected a direction");
    if (!std::isfinite(n)) r.fail_at("up", r.name("up") + ": its length is not a finite number");
    // the picture's up must not point along the view, or it cannot be set upright
    if (norm(cross(*c.up / n, view / norm(view))) < 1e-3)
      r.fail_at("up", r.name("up") +
                          " is parallel to the view direction (look_at - position): expected a "
                          "direction across it");
  } else if (norm(cross(Vec3{0, 0, 1}, view / norm(view))) < 1e-3) {
    r.fail_at("look_at", r.name("look_at") +
                             " is straight above or below camera.position, along the picture's "
                             "default up (z): set camera.up, a direction across the view");
  }
}

}  // namespace sandflow::loader

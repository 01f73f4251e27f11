#include "io/frame_exporter.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include <fmt/format.h>

#include "config/emitter_region.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "io/ply.hpp"
#include "io/vdb_export.hpp"
#include "surface/surface_params.hpp"

namespace sandflow {

namespace fs = std::filesystem;

namespace {

constexpr Real kInf = std::numeric_limits<Real>::infinity();
constexpr const char* kPovInclude = "pov_scene.inc";

// Half extents of an emitter's region and its top and bottom [m].
struct EmitterBox {
  Vec3 centre, half;
};

EmitterBox emitter_box(const EmitterConfig& e, Real d) {
  const Vec3 half = emitter_half_extent(e);
  if (e.type == EmitterType::Pour)  // a disk or rectangle of slots, a grain thick at least
    return {e.center, {half.x, half.y, std::max(half.z, d)}};
  return {e.center, half};
}

std::string frame_name(int frame, const char* ext) {
  return fmt::format("{:04d}{}", frame, ext);
}

}  // namespace

HeightRange run_height_range(const World& world) {
  const HeightField& hf = world.surface()->height_field();
  const SceneConfig& scene = world.scene();
  // H and h never go below L, and L is one of the solid tops
  Real lo = kInf, hi = -kInf;
  for (const Real t : hf.solids().top)
    if (std::isfinite(t)) lo = std::min(lo, t), hi = std::max(hi, t);
  const Real d = scene.material.largest_diameter();
  for (const EmitterConfig& e : scene.emitters) {
    const EmitterBox b = emitter_box(e, d);
    hi = std::max(hi, b.centre.z + b.half.z);
  }
  // a heap can rise above the highest solid by its own height at most
  hi += largest_heap(scene).height + d;
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo)) return {0, 1};
  return {lo, hi};
}

PovOptions fixed_pov_camera(const World& world) {
  const SceneConfig& scene = world.scene();
  const Geometry& geometry = world.geometry();
  const HeapSize heap = largest_heap(scene);
  const Real d = scene.material.largest_diameter();
  Vec3 lo, hi;
  bool have = geometry.finite_bounds(lo, hi);
  const auto grow = [&](const Vec3& a, const Vec3& b) {
    lo = have ? min(lo, a) : a;
    hi = have ? max(hi, b) : b;
    have = true;
  };
  // where the grains can go: each emitter's region widened by the largest heap, down to the
  // ground below it (or a heap's height below it when there is none), and where its throw comes
  // down
  for (const EmitterConfig& e : scene.emitters) {
    const EmitterBox b = emitter_box(e, d);
    if (const std::optional<Vec3> at = throw_landing(scene, e, geometry)) {
      const Vec3 spread{heap.radius, heap.radius, 0};
      grow(*at - Vec3{b.half.x, b.half.y, 0} - spread,
           *at + Vec3{b.half.x, b.half.y, heap.height} + spread);
    }
    const Real bottom = b.centre.z - b.half.z;
    const Real deepest = bottom - 1000;  // [m] a ground further down is not framed
    Real ground = geometry.top_below(b.centre.x, b.centre.y, bottom, deepest);
    if (ground <= deepest) ground = bottom - heap.height - d;
    const Vec3 spread{heap.radius, heap.radius, 0};
    grow(Vec3{b.centre.x, b.centre.y, ground} - Vec3{b.half.x, b.half.y, 0} - spread,
         b.centre + b.half + spread);
  }
  PovOptions opt;
  opt.auto_camera = false;
  if (!have) lo = {-0.5, -0.5, 0}, hi = {0.5, 0.5, 0.5};
  // as `sandflow render` looks: from 35 degrees up on the -y side, every corner of the box in the
  // picture with a 10 % border
  const Vec3 view = Vec3{1.0, -1.4, 1.2} / norm(Vec3{1.0, -1.4, 1.2});
  const Vec3 fwd = -view;
  const Vec3 right = cross(fwd, Vec3{0, 0, 1}) / norm(cross(fwd, Vec3{0, 0, 1}));
  const Vec3 up = cross(right, fwd);
  const double tan_h = 0.9 * std::tan(deg_to_rad(opt.fov_deg) / 2);
  const double tan_v = tan_h * opt.height / std::max(opt.width, 1);
  const Vec3 target = (lo + hi) * 0.5;
  double dist = 0.55 * norm(hi - lo) + 1e-3;  // outside the box at least
  for (int k = 0; k < 8; ++k) {
    const Vec3 p = Vec3{k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z} - target;
    dist = std::max(dist, std::abs(dot(p, right)) / tan_h - dot(p, fwd));
    dist = std::max(dist, std::abs(dot(p, up)) / tan_v - dot(p, fwd));
  }
  opt.camera_look_at = target;
  opt.camera_position = target + view * dist;
  return opt;
}

FrameExporter::FrameExporter(const World& world, const std::string& dir)
    : dir_(dir), up_(world.scene().output.up_axis) {
  const SceneConfig& scene = world.scene();
  std::vector<ExportFormat> dropped;
  if (scene.output.write_frames)
    formats_ = run_exports(scene.output, scene.simulation.mode, &dropped);
  if (!dropped.empty()) warnings_.push_back(dropped_exports_warning(scene.path, dropped));
  if (has(ExportFormat::Height) || has(ExportFormat::HeightObj)) {
    const fs::path hdir = fs::path(dir_) / "heightfield";
    std::error_code ec;
    fs::create_directories(hdir, ec);
    if (ec)
      throw OutputError(
          fmt::format("{}: cannot create the folder: {}", hdir.string(), ec.message()));
    range_ = run_height_range(world);
    write_file_atomic(
        (hdir / "heightfield.json").string(),
        height_sidecar(world.surface()->height_field().params(), range_, up_).dump(2) + "\n");
  }
  if (has(ExportFormat::Pov)) {
    // camera, lights, textures and the geometry, once: a scene with no grains
    std::vector<const TriangleMesh*> meshes(scene.geometry.size(), nullptr);
    for (const MeshObstacle& m : world.geometry().meshes())
      if (m.source >= 0 && static_cast<std::size_t>(m.source) < meshes.size())
        meshes[static_cast<std::size_t>(m.source)] = &m.mesh;
    write_pov_scene((fs::path(dir_) / "frames" / kPovInclude).string(), FrameData{}, scene.geometry,
                    fixed_pov_camera(world), meshes);
  }
}

void FrameExporter::continue_after(const std::vector<FrameStats>& done) {
  if (!has(ExportFormat::Vtk)) return;
  series_.clear();
  for (const FrameStats& st : done) series_.push_back({st.time, "frames/" + frame_name(st.frame, ".vtp")});
}

void FrameExporter::write_start(const World& world) {
  written_.clear();
  if (has(ExportFormat::Geo) || has(ExportFormat::GeoGz))
    write_houdini(world, world.visible_frame());
}

void FrameExporter::write_houdini(const World& world, const FrameData& f) {
  const fs::path frames = fs::path(dir_) / "frames";
  for (const ExportFormat format : {ExportFormat::Geo, ExportFormat::GeoGz})
    if (has(format)) {
      written_.push_back(
          (frames / houdini_frame_name(world.frame(), format == ExportFormat::GeoGz)).string());
      write_houdini_geo(written_.back(), f, up_);
    }
}

void FrameExporter::write(const World& world) {
  written_.clear();
  if (formats_.empty()) return;
  const int n = world.frame();
  const double t = world.time();
  const fs::path frames = fs::path(dir_) / "frames";
  const auto frame_file = [&](const char* ext) {
    written_.push_back((frames / frame_name(n, ext)).string());
    return written_.back();
  };
  const bool grains = has(ExportFormat::Ply) || has(ExportFormat::Vtk) || has(ExportFormat::Geo) ||
                      has(ExportFormat::GeoGz) || has(ExportFormat::Csv) || has(ExportFormat::Pov);
  const FrameData f = grains ? world.visible_frame() : FrameData{};
  if (has(ExportFormat::Ply)) write_ply(frame_file(".ply"), f, up_);
  if (has(ExportFormat::Vtk)) {
    write_vtk_legacy(frame_file(".vtk"), f, up_,
                     fmt::format("sandflow {} frame {}, t = {} s, {} visible grains, up axis {}",
                                 world.scene().name, n, t, f.size(), up_axis_name(up_)));
    write_vtp(frame_file(".vtp"), f, up_);
    series_.push_back({t, "frames/" + frame_name(n, ".vtp")});
    write_pvd((fs::path(dir_) / "frames.pvd").string(), series_);
  }
  write_houdini(world, f);
  if (has(ExportFormat::Csv)) write_grains_csv(frame_file(".csv"), f, up_);
  if (has(ExportFormat::Pov))
    write_file_atomic(
        frame_file(".pov"),
        fmt::format("// sandflow {} frame {}, t = {} s: {} visible grains. Render in "
                    "this folder, 16:9: povray +I{} +W1280 +H720\n#version 3.7;\n"
                    "#declare SandflowTime = {};\n#include \"{}\"\n",
                    world.scene().name, n, t, f.size(), frame_name(n, ".pov"), t, kPovInclude) +
            pov_grain_lines(f));
  if (has(ExportFormat::Vdb)) {
    const FrameData vdb_grains = grains ? FrameData{} : world.visible_frame();
    const SceneConfig& scene = world.scene();
    const bool surface = scene.simulation.mode == Mode::Surface && world.surface();
    write_vdb(frame_file(".vdb"), grains ? f : vdb_grains,
              surface ? &world.surface()->height_field() : nullptr,
              {scene.name, n, t, up_, vdb_points_voxel(scene.material), vdb_surface_voxel(scene)});
  }
  if (has(ExportFormat::Height) || has(ExportFormat::HeightObj)) {
    const HeightField& hf = world.surface()->height_field();
    const fs::path hdir = fs::path(dir_) / "heightfield";
    for (const auto& [name, z] :
         {std::pair<const char*, const std::vector<Real>*>{"H", &hf.surface()},
          {"h", &hf.static_top()}}) {
      const std::string stem = (hdir / fmt::format("{}_{:04d}", name, n)).string();
      if (has(ExportFormat::Height)) written_.push_back(stem + ".png");
      if (has(ExportFormat::HeightObj)) written_.push_back(stem + ".obj");
      if (has(ExportFormat::Height))
        clamped_ +=
            static_cast<std::int64_t>(write_height_png(stem + ".png", hf.params(), *z, range_));
      if (has(ExportFormat::HeightObj))
        write_height_obj(
            stem + ".obj", hf.params(), *z, up_,
            fmt::format("sandflow {} {} frame {}, t = {} s", world.scene().name, name, n, t));
    }
  }
}

nlohmann::json FrameExporter::summary() const {
  nlohmann::json names = nlohmann::json::array();
  for (const ExportFormat f : formats_) names.push_back(std::string(export_name(f)));
  nlohmann::json j = {{"formats", names}, {"up_axis", std::string(up_axis_name(up_))}};
  if (has(ExportFormat::Height)) {
    j["height_z_range"] = {range_.z_min, range_.z_max};
    j["height_clamped_values"] = clamped_;
  }
  return j;
}

}  // namespace sandflow

// The cost of the OpenVDB frame (`--export vdb`, io/vdb_export.hpp) on a heap of N grains
// (default 20,000), against the PLY frame of the same grains: bytes per grain and seconds per
// frame, each the median of 5 writes.
//
// The heap is made here, not simulated (a 20,000-grain pour takes minutes): the floor scene's
// grains (d = 1 cm, spread 0.1) filling a cone of 37.7 degrees (its 20,000-grain heaps, docs/
// performance.md) at a solid fraction of 0.58, on a jittered face-centred cubic lattice (the grains
// 8 % of a diameter apart). Two frames of it:
//   dem      every grain visible, no height field: a plain-DEM frame;
//   surface  the grains within 1.5 d of the cone's surface visible (R_min = d, then the
//            interface's T = d/2), the rest the static layer of a height field of 1 cm columns,
//            h = H - d: the shape of a surface-mode frame.
//   bench_vdb [N] [--threads T] [--out DIR]
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "core/rng.hpp"
#include "core/timer.hpp"
#include "io/ply.hpp"
#include "io/vdb_export.hpp"

using namespace sandflow;

namespace {

constexpr Real kD = 0.01, kSpread = 0.1, kSlope = 37.7 * kPi / 180, kSolidFraction = 0.58;

struct Heap {
  Real radius, height;  // of the cone [m]
  FrameData grains;
  /// H of the cone at (x, y) [m]
  Real top(Real x, Real y) const {
    return std::max(0.0, height - std::tan(kSlope) * std::hypot(x, y));
  }
};

// The grains of a cone of radius `radius`: a face-centred cubic packing, jittered, spaced so that
// it fills kSolidFraction.
Heap fill_cone(Real radius) {
  Heap heap;
  heap.radius = radius;
  heap.height = radius * std::tan(kSlope);
  const Real cube = std::cbrt(4 * kPi * kD * kD * kD / 6 / kSolidFraction);  // 4 grains a cube
  const Vec3 basis[4] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  Rng rng(1);
  const int m = static_cast<int>(std::ceil(radius / cube));
  for (int k = 0; k * cube < heap.height; ++k)
    for (int j = -m; j <= m; ++j)
      for (int i = -m; i <= m; ++i)
        for (const Vec3& b : basis) {
          const Real r = 0.5 * kD * (1 + kSpread * rng.uniform(-1, 1));
          const Vec3 jitter{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
          const Vec3 x =
              (Vec3{Real(i), Real(j), Real(k)} + b) * cube + Vec3{0, 0, r} + jitter * (0.02 * kD);
          if (x.z + r > heap.top(x.x, x.y)) continue;
          heap.grains.position.push_back(x);
          heap.grains.radius.push_back(r);
          // a heap at rest still creeps: velocities of random bits, which do not compress
          heap.grains.velocity.push_back(
              Vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)} * 1e-3);
          heap.grains.id.push_back(static_cast<std::uint32_t>(heap.grains.id.size()));
          heap.grains.state.push_back(static_cast<std::uint8_t>(rng.uniform(0, 1) < 0.5));
        }
  // ids in no order (a run files its grains by cell, not by id)
  for (std::size_t i = heap.grains.id.size(); i > 1; --i)
    std::swap(
        heap.grains.id[i - 1],
        heap.grains.id[static_cast<std::size_t>(rng.uniform(0, 1) * static_cast<Real>(i)) % i]);
  return heap;
}

// A cone holding about n grains: its radius from their volume, then corrected for the grains the
// cone's surface cuts off.
Heap make_heap(int n) {
  const Real volume = n * kPi * kD * kD * kD / 6 / kSolidFraction;
  Real radius = std::cbrt(3 * volume / (kPi * std::tan(kSlope)));
  Heap heap = fill_cone(radius);
  for (int k = 0; k < 3; ++k) {
    radius *= std::cbrt(n / static_cast<Real>(heap.grains.size()));
    heap = fill_cone(radius);
  }
  return heap;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <class F>
double seconds(F&& write) {
  std::vector<double> t;
  for (int k = 0; k < 5; ++k) {
    Stopwatch s;
    write();
    t.push_back(s.seconds());
  }
  return median(t);
}

}  // namespace

int main(int argc, char** argv) {
  int n = 20000;
  std::string out = (std::filesystem::temp_directory_path() / "sandflow_bench_vdb").string();
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--threads" && a + 1 < argc) {
      omp_set_num_threads(std::atoi(argv[++a]));
    } else if (arg == "--out" && a + 1 < argc) {
      out = argv[++a];
    } else {
      n = std::atoi(argv[a]);
    }
  }
  std::filesystem::create_directories(out);
  const Heap heap = make_heap(n);
  const std::size_t total = heap.grains.size();

  // the surface-mode frame: the grains near the cone's surface, the rest a static layer
  HeightFieldParams p;
  p.cell = kD;
  p.nx = p.ny = 2 * static_cast<int>(std::ceil(heap.radius / kD)) + 10;
  p.x0 = p.y0 = -0.5 * p.nx * kD;
  HeightField hf(p, std::vector<Real>(static_cast<std::size_t>(p.nx) * p.ny, 0.0));
  std::vector<Real> H(hf.columns()), h(hf.columns());
  for (std::size_t c = 0; c < hf.columns(); ++c) {
    H[c] = heap.top(hf.centre(c).x, hf.centre(c).y);
    h[c] = std::max(0.0, H[c] - kD);
  }
  hf.set_surface(H);
  hf.set_static_top(h);
  FrameData visible;
  for (std::size_t i = 0; i < total; ++i) {
    const Vec3& x = heap.grains.position[i];
    if (x.z < heap.top(x.x, x.y) - 1.5 * kD) continue;
    visible.position.push_back(x);
    visible.radius.push_back(heap.grains.radius[i]);
    visible.velocity.push_back(heap.grains.velocity[i]);
    visible.id.push_back(heap.grains.id[i]);
    visible.state.push_back(heap.grains.state[i]);
  }

  SceneConfig scene;
  scene.name = "bench_vdb";
  scene.material.diameter = kD;
  scene.material.diameter_spread = kSpread;
  VdbFrameInfo info;
  info.scene = scene.name;
  info.points_voxel = vdb_points_voxel(scene.material);
  info.surface_voxel = vdb_surface_voxel(scene);
  std::printf(
      "heap of %zu grains: cone radius %.3f m, height %.3f m; %d threads; voxels %.4g m "
      "(points), %.4g m (level set)\n",
      total, heap.radius, heap.height, omp_get_max_threads(), info.points_voxel,
      info.surface_voxel);
  std::printf("%-8s %8s %10s %12s %12s %10s %12s %10s\n", "frame", "visible", "vdb bytes",
              "B/visible", "B/grain", "vdb s", "ply bytes", "ply s");
  for (const bool surface : {false, true}) {
    const FrameData& f = surface ? visible : heap.grains;
    const std::string vdb_path = out + (surface ? "/surface.vdb" : "/dem.vdb");
    const std::string ply_path = out + (surface ? "/surface.ply" : "/dem.ply");
    const double vdb_s = seconds([&] { write_vdb(vdb_path, f, surface ? &hf : nullptr, info); });
    const double ply_s = seconds([&] { write_ply(ply_path, f); });
    const auto vdb_bytes = static_cast<double>(std::filesystem::file_size(vdb_path));
    const auto ply_bytes = static_cast<double>(std::filesystem::file_size(ply_path));
    std::printf("%-8s %8zu %10.0f %12.1f %12.1f %10.4f %12.0f %10.4f\n",
                surface ? "surface" : "dem", f.size(), vdb_bytes,
                vdb_bytes / static_cast<double>(f.size()), vdb_bytes / static_cast<double>(total),
                vdb_s, ply_bytes, ply_s);
  }
  std::printf("files in %s\n", out.c_str());
}

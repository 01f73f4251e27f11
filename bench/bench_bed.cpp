// The sandflow half of bench/compare_lammps.sh: monodisperse spheres (d = 2 mm, rho = 2500 kg/m^3,
// k_n = 500 N/m, k_t = 2/7 k_n, e = 0.5, mu = 0.5, no rolling resistance, dt = 1e-5 s) in a box,
// in one of two cases, each written as a LAMMPS data file so that both engines start from the
// same grains:
//   bed   100,000 grains settled in the box (cached in a file: settling takes minutes), then
//         2,000 steps timed: the steady cost of the contact law;
//   pour  a loose column of grains at rest above the middle of the floor, released at t = 0 and
//         timed from there while it lands and spreads into a heap: grains arriving over time, the
//         work of a user's pour, where the contacts and the rebuilds move with the grains.
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <fmt/format.h>

#include "core/rng.hpp"
#include "core/timer.hpp"
#include "dem/dem_solver.hpp"
#include "sim/world.hpp"

using namespace sandflow;

namespace {

constexpr Real kD = 0.002, kRho = 2500, kKn = 500, kE = 0.5, kMu = 0.5, kDt = 1e-5;
// A settled random bed of equal frictional spheres touches 4-6 neighbours a grain; below 3 it is
// still falling or loose.
constexpr double kMinContactsPerGrain = 3.0;
// What the cached bed depends on: a cache written with other values, or by another version of
// this file's bed, is built again rather than reused.
std::string bed_key(std::int64_t n) {
  return fmt::format("SFBED002 n={} d={} rho={} kn={} e={} mu={} dt={} lattice=1.1,jitter=1", n,
                     kD, kRho, kKn, kE, kMu, kDt);
}

struct Bed {
  Real side = 0;  ///< box footprint side [m]
  Grains grains;
};

MaterialConfig bed_material() {
  MaterialConfig m;
  m.density = kRho;
  m.diameter = kD;
  m.diameter_spread = 0;
  m.k_n = kKn;
  m.k_t_ratio = 2.0 / 7.0;
  m.restitution = kE;
  m.tangential_damping_ratio = 0.5;
  m.friction = kMu;
  m.rolling_friction = 0;
  m.wall_friction = kMu;
  m.wall_rolling_friction = 0;
  return m;
}

std::vector<GeometryConfig> bed_walls(Real side) {
  auto plane = [](Vec3 p, Vec3 n) {
    GeometryConfig g;
    g.type = GeometryType::Plane;
    g.point = p;
    g.normal = n;
    return g;
  };
  return {plane({0, 0, 0}, {0, 0, 1}), plane({0, 0, 0}, {1, 0, 0}), plane({side, 0, 0}, {-1, 0, 0}),
          plane({0, 0, 0}, {0, 1, 0}), plane({0, side, 0}, {0, -1, 0})};
}

// A loose jittered lattice dropped into the box and left to settle.
Bed make_bed(std::int64_t n, int settle_frames) {
  SceneConfig scene;
  scene.path = "bench_bed";
  scene.name = "bed";
  scene.material = bed_material();
  scene.simulation.mode = Mode::Dem;  // every grain simulated: a surface run would put some to sleep
  scene.simulation.dt = kDt;
  scene.output.fps = 100;  // a frame = 1,000 steps
  // footprint: about 1/1000 of N grains per layer, at least 20 x 20
  const Real per_side = std::max(20.0, std::round(std::sqrt(static_cast<Real>(n) / 40.0)));
  Bed bed;
  bed.side = per_side * kD * 1.1;
  scene.geometry = bed_walls(bed.side);
  EmitterConfig e;
  e.type = EmitterType::Block;
  e.count = n;
  e.spacing = 1.1;
  e.jitter = 1.0;
  const Real layers = std::ceil(static_cast<Real>(n) / (per_side * per_side)) + 1;
  e.size = {bed.side, bed.side, layers * kD * 1.1};
  e.center = {bed.side / 2, bed.side / 2, e.size.z / 2};
  scene.emitters = {e};
  World world(scene);
  // settle until the grains are nearly still (mean speed ~ 4 mm/s) or the frames run out
  bool still = false;
  double contacts_per_grain = 0;
  for (int f = 0; f < settle_frames && !still; ++f) {
    const FrameStats st = world.advance_frame();
    contacts_per_grain = 2.0 * st.contacts / static_cast<double>(st.n_total);
    std::fprintf(stderr,
                 "settling: t = %.2f s, grains %lld (%lld left the domain), kinetic energy %.3e J, "
                 "contacts/grain %.2f\n",
                 st.time, static_cast<long long>(st.n_total),
                 static_cast<long long>(world.left_domain()), st.kinetic_energy,
                 contacts_per_grain);
    still = f >= 10 && st.kinetic_energy < 1e-10 * static_cast<double>(st.n_total);
  }
  bed.grains = world.grains();
  // a bed that is not whole, not still or not packed is never timed nor cached
  const auto held = static_cast<std::int64_t>(bed.grains.size());
  if (held != n || !still || contacts_per_grain < kMinContactsPerGrain) {
    std::fprintf(stderr,
                 "bench_bed: the bed is not settled after %d frames: %lld of %lld grains, %s, "
                 "%.2f contacts per grain (at least %.1f wanted); raise --settle-frames\n",
                 settle_frames, static_cast<long long>(held), static_cast<long long>(n),
                 still ? "still" : "still moving", contacts_per_grain, kMinContactsPerGrain);
    std::exit(1);
  }
  return bed;
}

// A pour: a column of n grains on a loose lattice (spacing 1.5 d, each grain jittered by up to
// 0.2 d, so no two touch and no column of grains stands on another), its foot 2 d above the
// middle of a box twice as wide, at rest. Without rolling resistance (LAMMPS's
// gran/hooke/history has none) spheres on a flat floor roll apart rather than stand in a heap, so
// the box holds them: they land, spread to its walls and pile into a bed about ten grains deep.
Bed make_column(std::int64_t n) {
  const Real cbrt_n = std::cbrt(static_cast<Real>(n));
  const auto across = static_cast<std::int64_t>(std::max(3.0, std::round(0.7 * cbrt_n)));
  const Real pitch = 1.5 * kD;
  Bed bed;
  bed.side = 2 * pitch * static_cast<Real>(across);
  const Real x0 = bed.side / 2 - 0.5 * pitch * static_cast<Real>(across - 1);
  Rng rng(20261126);
  for (std::int64_t k = 0; k < n; ++k) {
    const std::int64_t layer = k / (across * across), in_layer = k % (across * across);
    const Vec3 lattice{x0 + pitch * static_cast<Real>(in_layer % across),
                       x0 + pitch * static_cast<Real>(in_layer / across),
                       2.5 * kD + pitch * static_cast<Real>(layer)};
    const Vec3 jitter{rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1)};
    bed.grains.add(static_cast<GrainId>(k), lattice + jitter * kD, Vec3{}, kD / 2, kRho);
  }
  return bed;
}

template <class T>
void put(std::ofstream& o, const std::vector<T>& a) {
  o.write(reinterpret_cast<const char*>(a.data()), static_cast<std::streamsize>(a.size() * sizeof(T)));
}
template <class T>
void get(std::ifstream& i, std::vector<T>& a, std::size_t n) {
  a.resize(n);
  i.read(reinterpret_cast<char*>(a.data()), static_cast<std::streamsize>(n * sizeof(T)));
}

void save_bed(const std::string& path, const Bed& b) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream o(path + ".tmp", std::ios::binary);
  const std::uint64_t n = b.grains.size();
  const std::string key = bed_key(static_cast<std::int64_t>(n));
  const std::uint64_t key_size = key.size();
  o.write(reinterpret_cast<const char*>(&key_size), 8);
  o.write(key.data(), static_cast<std::streamsize>(key.size()));
  o.write(reinterpret_cast<const char*>(&n), 8);
  o.write(reinterpret_cast<const char*>(&b.side), 8);
  put(o, b.grains.id), put(o, b.grains.x), put(o, b.grains.v), put(o, b.grains.w), put(o, b.grains.r);
  o.close();
  std::filesystem::rename(path + ".tmp", path);
}

// Reads a cached bed of `expected` grains; false when there is none, or it was built otherwise.
bool load_bed(const std::string& path, std::int64_t expected, Bed& b) {
  std::ifstream i(path, std::ios::binary);
  const std::string want = bed_key(expected);
  std::uint64_t key_size = 0, n = 0;
  if (!i.read(reinterpret_cast<char*>(&key_size), 8) || key_size != want.size()) return false;
  std::string key(key_size, '\0');
  if (!i.read(key.data(), static_cast<std::streamsize>(key_size)) || key != want) return false;
  i.read(reinterpret_cast<char*>(&n), 8);
  if (static_cast<std::int64_t>(n) != expected) return false;
  i.read(reinterpret_cast<char*>(&b.side), 8);
  std::vector<GrainId> id;
  std::vector<Vec3> x, v, w;
  std::vector<Real> r;
  get(i, id, n), get(i, x, n), get(i, v, n), get(i, w, n), get(i, r, n);
  if (!i) return false;
  b.grains = {};
  for (std::size_t k = 0; k < n; ++k) {
    b.grains.add(id[k], x[k], v[k], r[k], kRho);
    b.grains.w.back() = w[k];
  }
  return true;
}

void write_lammps(const std::string& path, const Bed& b) {
  Real top = 0;
  for (const Vec3& p : b.grains.x) top = std::max(top, p.z);
  std::ofstream o(path);
  o << fmt::format("sandflow settled bed\n\n{} atoms\n1 atom types\n\n", b.grains.size());
  o << fmt::format("0 {:.10g} xlo xhi\n0 {:.10g} ylo yhi\n0 {:.10g} zlo zhi\n\n", b.side, b.side,
                   2 * top + 0.01);
  o << "Atoms # sphere\n\n";
  for (std::size_t k = 0; k < b.grains.size(); ++k) {
    const Vec3& p = b.grains.x[k];
    o << fmt::format("{} 1 {:.10g} {} {:.12g} {:.12g} {:.12g}\n", k + 1, 2 * b.grains.r[k], kRho,
                     p.x, p.y, p.z);
  }
  o << "\nVelocities\n\n";
  for (std::size_t k = 0; k < b.grains.size(); ++k) {
    const Vec3& v = b.grains.v[k];
    const Vec3& w = b.grains.w[k];
    o << fmt::format("{} {:.10g} {:.10g} {:.10g} {:.10g} {:.10g} {:.10g}\n", k + 1, v.x, v.y, v.z,
                     w.x, w.y, w.z);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::int64_t n = 100000;
  int threads = 1, steps = 2000, settle_frames = 60;
  std::string bench_case = "bed", bed_path, lammps_path;
  double skin = 0.2, skin_max = 0;  // [d]
  int skin_steps = 0;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    auto next = [&]() -> std::string {
      if (k + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++k];
    };
    if (a == "--case")
      bench_case = next();
    else if (a == "--grains")
      n = std::stoll(next());
    else if (a == "--threads") threads = std::stoi(next());
    else if (a == "--steps") steps = std::stoi(next());
    else if (a == "--settle-frames") settle_frames = std::stoi(next());
    else if (a == "--bed") bed_path = next();
    else if (a == "--write-lammps") lammps_path = next();
    else if (a == "--skin")
      skin = std::stod(next());
    else if (a == "--skin-steps")
      skin_steps = std::stoi(next());
    else if (a == "--skin-max")
      skin_max = std::stod(next());
    else {
      std::fprintf(stderr,
                   "usage: bench_bed [--case bed|pour] [--grains N] [--threads T] [--steps S] "
                   "[--settle-frames F] [--bed FILE] [--write-lammps FILE] [--skin S] "
                   "[--skin-steps K] [--skin-max M]\n");
      return 2;
    }
  }
  if (bench_case != "bed" && bench_case != "pour") {
    std::fprintf(stderr, "--case %s: expected bed or pour\n", bench_case.c_str());
    return 2;
  }
  if (n < 1 || steps < 1) {
    std::fprintf(stderr, "--grains and --steps must be at least 1\n");
    return 2;
  }
  if (!(skin > 0) || skin_steps < 0 || !(skin_max >= 0)) {
    std::fprintf(stderr, "--skin must be above 0, --skin-steps and --skin-max at least 0\n");
    return 2;
  }
  const bool pour = bench_case == "pour";
  omp_set_num_threads(std::max(2, threads));  // settle with both cores
  Bed bed;
  if (pour) {
    bed = make_column(n);
  } else if (bed_path.empty() || !load_bed(bed_path, n, bed)) {
    if (!bed_path.empty()) std::fprintf(stderr, "no cached bed for this build of it: settling one\n");
    bed = make_bed(n, settle_frames);
    if (!bed_path.empty()) save_bed(bed_path, bed);
  }
  if (!lammps_path.empty()) write_lammps(lammps_path, bed);
  omp_set_num_threads(threads);

  // time the settled bed with the DEM layer alone, the part LAMMPS's run loop does too
  const MaterialConfig mat = bed_material();
  DemParams params;
  params.contact = contact_params(mat);
  params.skin = skin * kD;
  params.skin_steps = skin_steps;
  params.skin_max = skin_max * kD;
  const Geometry geometry = Geometry::from_config(bed_walls(bed.side), mat);
  DemSolver dem(params);
  Profile profile;
  // the bed: a warm-up builds the contact history; the pour is timed from its release, as LAMMPS
  if (!pour)
    for (int s = 0; s < 200; ++s) dem.step(bed.grains, geometry, kDt, profile);
  profile = {};
  dem.counters() = {};
  Stopwatch clock;
  for (int s = 0; s < steps; ++s) dem.step(bed.grains, geometry, kDt, profile);
  const double seconds = clock.seconds();
  const auto grains = static_cast<double>(bed.grains.size());
  std::printf(
      "stages: neighbours %.3f s, forces and integration %.3f s, rebuilds %lld, near lists %lld\n",
      profile[Stage::Neighbours], profile[Stage::Forces],
      static_cast<long long>(dem.counters().rebuilds),
      static_cast<long long>(dem.counters().near_builds));
  double near_pairs = 0;
  for (std::uint32_t c : dem.pairs().near_count) near_pairs += c;
  std::printf("listed pairs per grain %.2f (half list, skin %.3g d), %.2f near\n",
              static_cast<double>(dem.pairs().pairs()) / grains, skin, near_pairs / grains);
  std::printf("damping beta=%.12g (restitution %.2f under the clamped law)\n", params.contact.beta,
              kE);
  // where the grains ended: a pour's two engines do not follow the same chaotic paths, but they
  // must make the same heap (compare_lammps.sh compares these with LAMMPS's)
  Real mean_z = 0;
  for (const Vec3& p : bed.grains.x) mean_z += p.z / grains;
  std::printf(
      "engine=sandflow case=%s threads=%d grains=%lld steps=%d seconds=%.4f "
      "grain_steps_per_s=%.6g contacts_per_grain=%.4f mean_z=%.6g\n",
      bench_case.c_str(), threads, static_cast<long long>(bed.grains.size()), steps, seconds,
      grains * steps / seconds, 2.0 * static_cast<double>(dem.counters().contacts) / grains,
      mean_z);
  return 0;
}

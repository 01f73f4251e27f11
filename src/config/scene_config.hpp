// A scene as plain data, after parsing and validation: every field in SI units, angles already in
// radians where the struct says so. The loader (scene/scene_loader.hpp) fills it from a TOML file;
// the World is built from it. Defaults here are the documented defaults of docs/scenes.md.
// It is a leaf of the layers (docs/design.md): plain structs over core/, read by every layer above.
#pragma once

#include <array>
#include <cstdint>
#include <initializer_list>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/vec3.hpp"

namespace sandflow {

enum class Mode { Surface, Dem };

struct MaterialConfig {
  Real density = 2600.0;            ///< grain density [kg/m^3]
  Real diameter = 0.01;             ///< mean grain diameter [m]
  Real diameter_spread = 0.0;       ///< radii uniform in d*(1 +- spread)/2 [-], in [0, 0.5]
  Real k_n = 1.0e4;                 ///< normal stiffness [N/m]
  Real k_t_ratio = 2.0 / 7.0;       ///< tangential stiffness k_t / k_n [-]
  Real restitution = 0.3;           ///< normal coefficient of restitution e, in (0, 1]
  Real tangential_damping_ratio = 0.5;  ///< c_t / c_n [-]
  Real friction = 0.6;              ///< Coulomb friction mu between grains [-]
  Real rolling_friction = 0.1;      ///< rolling resistance mu_r (torque cap mu_r R_eff |F_n|) [-]
  Real rolling_stiffness_ratio = 1.0;  ///< k_r / k_t: stiffness of the rolling spring [-]
  Real rolling_damping_ratio = 1.0;    ///< c_r / c_t [-]
  Real twisting_friction = 0;  ///< twisting resistance mu_tw (torque cap mu_tw R_eff |F_n|) [-]
  Real wall_friction = 0.6;         ///< Coulomb friction between grains and geometry [-]
  Real wall_rolling_friction = 0.1; ///< rolling resistance between grains and geometry [-]
  Real wall_twisting_friction = 0;  ///< twisting resistance between grains and geometry [-]

  /// The largest grain's diameter [m].
  Real largest_diameter() const { return diameter * (1 + diameter_spread); }
  /// The smallest grain's diameter [m].
  Real smallest_diameter() const { return diameter * (1 - diameter_spread); }
};

/// Deriving k_n from the load a contact carries (docs/design.md §3), separately for each mode. Used
/// when `from_load` is set; material.k_n is then ignored.
struct StiffnessConfig {
  bool from_load = false;
  Real max_overlap = 0.01;          ///< largest static overlap wanted, fraction of a diameter [-]
  Real impact_overlap = 0.1;        ///< largest overlap wanted in an impact, fraction of d [-]
  std::optional<Real> impact_speed; ///< fastest impact [m/s]; unset: from the emitters
  std::optional<Real> dem_depth;    ///< deepest loaded grain in DEM mode [m]; unset: heap height
  std::optional<Real> surface_depth;///< deepest loaded grain in surface mode [m]; unset: R_min+T+2d
};

/// The height field and the particle interface (docs/design.md §4, §5). Unset values take defaults
/// derived from the material (surface/surface_params.hpp); angles in radians.
struct SurfaceConfig {
  std::optional<Real> cell_size;            ///< column width [m]; default: mean diameter
  std::optional<Real> exchange_rate;        ///< gamma [1/s]; default 5 sqrt(g / d)
  Real repose_angle = deg_to_rad(32.0);     ///< theta_0 [rad]
  std::optional<Real> max_angle;            ///< theta_max [rad]; default theta_0 + 6 deg
  bool repose_angle_given = false;          ///< set by the scene (else calibrated, or the default)
  /// Where the angles came from, for summary.json: "scene", "calibration KEY (cached|measured)",
  /// or "" (the scene's, or the built-in defaults where it sets none)
  std::string angles_source;
  std::optional<Real> rolling_min;          ///< R_min [m]; default one mean diameter
  std::optional<Real> flowing_min;          ///< R_min under a flowing layer [m]; default 2 d
  Real flowing_hold = 0.5;                  ///< how long a stopped flow keeps flowing_min [s]
  /// a flowing column erodes where a moving grain's bottom lies within this of h [m]; default d/2
  std::optional<Real> erosion_reach;
  Real close_after = 2.0;                   ///< rest after which a column's top freezes [s]
  /// a body striking the bed opens it as far as its whole momentum reaches (the blow rule)
  bool blows = false;
  std::optional<Real> interface_thickness;  ///< T [m]; default half a mean diameter
  std::optional<Real> update_interval;      ///< time between height-field updates [s]
  std::optional<Real> trap_speed;           ///< grains slower than this may be trapped [m/s]
  /// a grain touching the pile faster than this makes the rolling layer flow and digs [m/s]
  std::optional<Real> flow_speed;
  std::optional<std::array<Real, 4>> extent;  ///< [x0, y0, x1, y1] of the grid [m]; unset: auto
};

/// What a grain that leaves the domain does to the run (simulation.on_leave).
enum class OnLeave { Stop, Count };

struct SimulationConfig {
  Mode mode = Mode::Surface;        ///< surface: height field + DEM; dem: plain DEM
  Vec3 gravity{0, 0, -9.81};        ///< [m/s^2]
  std::optional<Real> dt;           ///< fixed time step [s]; unset: dt_fraction * t_c
  Real dt_fraction = 0.05;          ///< dt = dt_fraction * t_c when dt is unset (t_c/20)
  Real skin = 0.2;                  ///< Verlet skin as a fraction of the mean diameter [-]
  int skin_steps = 32;              ///< a fast grain's allowance: this many steps at its speed
  Real skin_max = 1.0;              ///< largest allowance, as a fraction of the mean diameter [-]
  int sort_every = 20;              ///< re-sort grains by cell every N neighbour rebuilds
  std::uint64_t seed = 1;           ///< random seed of the emitters
  int threads = 0;                  ///< 0: all cores
  // guards (docs/scenes.md): a run that leaves its valid range stops, naming the step and grain
  Real max_overlap_stop = 0.6;      ///< stop when an overlap exceeds this fraction of a diameter
  /// [x0, y0, z0, x1, y1, z1] the grains must stay in [m]; unset: derived from the scene
  std::optional<std::array<Real, 6>> domain;
  OnLeave on_leave = OnLeave::Stop; ///< a grain leaving the domain stops the run, or is removed
};

/// The files a run writes each frame (output.export, --export; docs/scenes.md "Exports").
enum class ExportFormat { Ply, Vtk, Geo, GeoGz, Pov, Csv, Height, HeightObj, Vdb };
/// The up axis of exported coordinates: the scene's z, or y (the scene's z becomes y).
enum class UpAxis { Z, Y };

struct OutputConfig {
  Real fps = 30.0;                  ///< frames per simulated second [1/s]
  std::optional<Real> duration;     ///< simulated time [s]; unset: end of emission + settle_time
  Real settle_time = 1.5;           ///< [s] after the last grain is emitted (duration unset)
  std::optional<int> frames;        ///< explicit frame count (from --frames)
  bool write_frames = true;         ///< write the per-frame files of `exports`
  /// unset: the default, ply (and height in surface mode); empty: no per-frame files
  std::optional<std::vector<ExportFormat>> exports;
  UpAxis up_axis = UpAxis::Z;          ///< of PLY, VTK, geo, CSV, OBJ and VDB files
  std::optional<Real> vdb_voxel_size;  ///< of the VDB level set [m]; unset: a third of d_min
};

/// The camera of `sandflow render`: a fixed one when position and look_at are set, else the
/// automatic one that frames the whole run.
struct CameraConfig {
  std::optional<Vec3> position;     ///< [m]; set together with look_at
  std::optional<Vec3> look_at;      ///< [m]
  std::optional<Vec3> up;           ///< the picture's up direction; unset: +z (fixed camera only)
  Real fov_deg = 40.0;              ///< horizontal field of view [deg], in (0, 180)
};

enum class GeometryType { Plane, Box, Cylinder, Sphere, Bowl, Heightmap, Mesh };
enum class RenderStyle { Solid, Glass, Hidden };
/// Where a heightmap's samples came from: written in the scene, a grey PNG, or made by noise.
enum class HeightSource { Inline, File, Noise };

/// A rectangular grid of heights over a heightmap's extent [x0, y0, x1, y1]: nx samples along x
/// (one row) by ny rows along y, z[j * nx + i] at x0 + i (x1 - x0)/(nx - 1), y0 + j (y1 - y0)/(ny - 1).
struct HeightGrid {
  int nx = 0;
  int ny = 0;
  std::vector<Real> z;  ///< [m]
  bool operator==(const HeightGrid&) const = default;
};

struct GeometryConfig {
  GeometryType type = GeometryType::Plane;
  std::string name;                 ///< for messages and rendering
  RenderStyle render = RenderStyle::Solid;
  std::optional<Real> friction;     ///< overrides material.wall_friction
  std::optional<Real> remove_at;    ///< the solid vanishes at this time [s] (a gate, a lifted tube)
  // plane
  Vec3 point{0, 0, 0};              ///< a point of the plane [m]
  Vec3 normal{0, 0, 1};             ///< unit normal, pointing to the free side
  // box, cylinder, sphere
  Vec3 center{0, 0, 0};             ///< [m]
  Vec3 size{1, 1, 1};               ///< box: full extents along its local axes [m]
  Vec3 rotation_deg{0, 0, 0};       ///< box, cylinder: Euler angles about x, y, z [deg]
  Real radius = 0.5;                ///< cylinder, sphere [m]
  Real height = 1.0;                ///< cylinder: length along its axis (local z) [m]
  bool container = false;           ///< box, cylinder: grains live inside, behind walls
  bool open_top = true;             ///< container: no lid
  Real wall_thickness = 0.02;       ///< container walls; bowl: thickness of its shell [m]
  // bowl: a spherical shell of inner radius `radius` around `center`, cut by the rim plane
  std::optional<Real> depth;        ///< inner bottom below the rim plane [m]; unset: radius
  // heightmap: solid from its bottom up to z = f(x, y) over `extent`
  std::array<Real, 4> extent{0, 0, 1, 1};  ///< [x0, y0, x1, y1] [m]
  HeightSource height_source = HeightSource::Inline;
  HeightGrid heights;               ///< the samples, whatever their source (the loader fills it)
  std::string file;                 ///< height_source File: the PNG, resolved against the scene
  Real z_min = 0.0;                 ///< File, Noise: height of the lowest grey / noise value [m]
  Real z_max = 0.1;                 ///< File, Noise: height of the highest grey / noise value [m]
  Real noise_wavelength = 0.2;      ///< Noise: mean wavelength of its waves [m]
  std::uint64_t noise_seed = 1;     ///< Noise: seed of the wave directions and phases
  Real base_thickness = 0.05;       ///< the solid reaches this far below its lowest sample [m]
  // mesh
  std::string mesh_file;  ///< OBJ, PLY, OFF, STL or glTF (maybe .gz), as written (key `file`)
  std::optional<Real> scale;        ///< multiplies the file's coordinates [-]
  std::optional<Real> mesh_size;    ///< or: the largest extent after scaling [m] (key `size`)
  Vec3 position{0, 0, 0};           ///< where the centre of the bottom of its bounds goes [m]
  bool fallback_box = false;        ///< a missing file gives a box of fallback_size (warned)
  Vec3 fallback_size{0.3, 0.3, 0.3};  ///< [m]
  std::optional<Real> particle_radius;  ///< boundary particles [m]; unset: half the smallest d
  bool operator==(const GeometryConfig&) const = default;
};

enum class EmitterType { Pour, Block, Lattice, Bed };
enum class PourShape { Disk, Rect };
/// Which way a pour's area faces: up z (it lies level) or along its velocity (a nozzle).
enum class PourFacing { Up, Velocity };

struct EmitterConfig {
  EmitterType type = EmitterType::Pour;
  std::string name;
  std::int64_t count = 0;           ///< grains this emitter makes in total
  Real start = 0.0;                 ///< time of the first grain [s]
  Vec3 velocity{0, 0, 0};           ///< initial velocity [m/s]
  Real jitter = 0.25;               ///< random offset, as a fraction of the free gap [-], [0, 1]
  // pour
  PourShape shape = PourShape::Disk;
  PourFacing facing = PourFacing::Up;
  Vec3 center{0, 0, 0};             ///< pour: centre of the disk/rectangle; block: box centre
  Real radius = 0.05;               ///< pour disk radius [m]
  Vec3 size{0.1, 0.1, 0.1};         ///< pour rect: its two extents (z ignored); block/lattice: box
  Real rate = 1000.0;               ///< pour rate [grains/s]
  Real rate_scale = 1.0;            ///< what scale_grain_count multiplied the scene's rate by
  Real spacing = 1.05;              ///< lattice/slot spacing as a multiple of the largest diameter
  // bed: a packed region at rest over the footprint center.xy +- size.xy / 2, from the scene's
  // geometry up to z = height. Its count is the packing's (resolve_beds, sim/emitters.hpp), and
  // center.z and size.z become the box of its grains.
  Real height = 0.0;  ///< the bed's top [m]: flat, or the highest point of its relief
  Real relief = 0.0;  ///< depth of the top's relief below `height` [m]; 0: a flat top
  std::optional<Real> relief_wavelength;  ///< of the relief [m]; unset: a quarter of the footprint
  std::uint64_t relief_seed = 1;          ///< the relief's shape (the same for every run seed)
};

struct SceneConfig {
  std::string path;                 ///< file it came from
  std::string name;
  std::string description;
  MaterialConfig material;
  SimulationConfig simulation;
  StiffnessConfig stiffness;
  SurfaceConfig surface;
  OutputConfig output;
  CameraConfig camera;
  std::vector<GeometryConfig> geometry;
  std::vector<EmitterConfig> emitters;

  /// Where each key read came from ("PATH:LINE:COL", or "--set KEY" for an override), by its
  /// name in messages ("emitter[0].rate"), with its line (0 for an override).
  struct KeyPlace {
    std::string text;
    int line = 0;
  };
  std::map<std::string, KeyPlace, std::less<>> key_places;
  /// The loader's warnings, "PLACE: what": keys the scene gave that nothing uses, angles that look
  /// like radians. Each run prints them.
  std::vector<std::string> warnings;

  std::int64_t total_grains() const {
    std::int64_t n = 0;
    for (const auto& e : emitters) n += e.count;
    return n;
  }

  /// The place of the first of `keys` the scene gave ("material.k_n"), or of a table
  /// ("emitter[0]": its first key in the file), so that an error found after loading, about
  /// keys checked together, points at a line as the loader's own do; else the file.
  std::string place(std::initializer_list<std::string_view> keys) const {
    for (std::string_view key : keys) {
      if (const auto it = key_places.find(key); it != key_places.end()) return it->second.text;
      const KeyPlace* first = nullptr;
      const std::string prefix = std::string(key) + ".";
      for (auto it = key_places.lower_bound(prefix);
           it != key_places.end() && it->first.compare(0, prefix.size(), prefix) == 0; ++it)
        if (!first || (it->second.line > 0 && (first->line == 0 || it->second.line < first->line)))
          first = &it->second;
      if (first) return first->text;
    }
    return path;
  }
};

}  // namespace sandflow

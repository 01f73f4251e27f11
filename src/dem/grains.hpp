// Grains in the three states of docs/design.md §2, stored as structure of arrays.
//
// The hot store holds the grains that take part in DEM: ACTIVE ones (integrated) and INTERFACE
// ones (fixed, but they push). Each property is one contiguous array, indexed by a slot that
// changes when grains are re-sorted by cell; `id` is the stable identity of a grain. STATIC grains
// live in a separate cold store that costs only a position and a radius (and the column that
// files them, so erosion can wake them).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/vec3.hpp"

namespace sandflow {

enum class GrainState : std::uint8_t { Active = 0, Interface = 1, Static = 2 };

using GrainId = std::uint32_t;

/// ACTIVE and INTERFACE grains: everything the DEM step reads and writes.
struct Grains {
  std::vector<GrainId> id;
  std::vector<GrainState> state;
  std::vector<Vec3> x;       ///< centre [m]
  std::vector<Vec3> v;       ///< velocity [m/s]
  std::vector<Vec3> w;       ///< angular velocity [rad/s]
  std::vector<Real> r;       ///< radius [m]
  std::vector<Real> m;       ///< mass [kg]
  std::vector<Real> inv_m;   ///< 1/mass [1/kg]
  std::vector<Real> inv_I;   ///< 1/moment of inertia (solid sphere) [1/(kg m^2)]

  std::size_t size() const { return id.size(); }

  /// Appends an ACTIVE grain of the given density.
  void add(GrainId gid, const Vec3& pos, const Vec3& vel, Real radius, Real density);

  /// Reorders every array so that slot k holds what slot perm[k] held; a shorter perm keeps only
  /// the grains it names.
  void permute(std::span<const std::uint32_t> perm);
};

/// STATIC grains: position and radius only, filed by height-field column.
struct StaticStore {
  std::vector<GrainId> id;
  std::vector<Vec3> x;
  std::vector<Real> r;
  std::vector<std::uint32_t> column;
  // the grains of each column, valid after file_by_column()
  std::vector<std::uint32_t> column_start;  ///< columns+1 offsets into by_column
  std::vector<std::uint32_t> by_column;     ///< slots, grouped by column, each column's by height
  /// Counts every change, so that an index built on the store knows when it is stale.
  std::uint64_t revision = 0;

  std::size_t size() const { return id.size(); }
  void add(GrainId gid, const Vec3& pos, Real radius, std::uint32_t col);
  /// As Grains::permute (the column index must be rebuilt after).
  void permute(std::span<const std::uint32_t> perm);
  /// Files every grain by its column (counting sort), each column's grains in ascending z.
  void file_by_column(std::size_t columns);
};

/// The invariant of the stores (docs/design.md §2), for assertions: every array of each store has
/// its size, the hot store holds no STATIC grain, every id is below `next_id` and held at most
/// once in the two stores together, and they hold `expected` grains (so each of those is in
/// exactly one). Returns what is wrong, or "" when nothing is. O(n + next_id).
std::string store_error(const Grains& hot, const StaticStore& statics, GrainId next_id,
                        std::int64_t expected);

}  // namespace sandflow

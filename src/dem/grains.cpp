#include "dem/grains.hpp"

#include <algorithm>
#include <utility>

#include <fmt/format.h>

namespace sandflow {

void Grains::add(GrainId gid, const Vec3& pos, const Vec3& vel, Real radius, Real density) {
  const Real mass = density * (4.0 / 3.0) * kPi * radius * radius * radius;
  id.push_back(gid);
  state.push_back(GrainState::Active);
  x.push_back(pos);
  v.push_back(vel);
  w.push_back({});
  r.push_back(radius);
  m.push_back(mass);
  inv_m.push_back(1.0 / mass);
  inv_I.push_back(1.0 / (0.4 * mass * radius * radius));
}

namespace {
template <class T>
void apply_permutation(std::vector<T>& a, std::span<const std::uint32_t> perm) {
  std::vector<T> out(perm.size());
  for (std::size_t k = 0; k < perm.size(); ++k) out[k] = a[perm[k]];
  a = std::move(out);
}
}  // namespace

void Grains::permute(std::span<const std::uint32_t> perm) {
  apply_permutation(id, perm);
  apply_permutation(state, perm);
  apply_permutation(x, perm);
  apply_permutation(v, perm);
  apply_permutation(w, perm);
  apply_permutation(r, perm);
  apply_permutation(m, perm);
  apply_permutation(inv_m, perm);
  apply_permutation(inv_I, perm);
}

void StaticStore::add(GrainId gid, const Vec3& pos, Real radius, std::uint32_t col) {
  id.push_back(gid);
  x.push_back(pos);
  r.push_back(radius);
  column.push_back(col);
  ++revision;
}

void StaticStore::permute(std::span<const std::uint32_t> perm) {
  apply_permutation(id, perm);
  apply_permutation(x, perm);
  apply_permutation(r, perm);
  apply_permutation(column, perm);
  ++revision;
}

void StaticStore::file_by_column(std::size_t columns) {
  column_start.assign(columns + 1, 0);
  for (std::uint32_t c : column) ++column_start[c + 1];
  for (std::size_t c = 0; c < columns; ++c) column_start[c + 1] += column_start[c];
  by_column.resize(size());
  std::vector<std::uint32_t> fill(column_start.begin(), column_start.end() - 1);
  for (std::uint32_t k = 0; k < size(); ++k) by_column[fill[column[k]]++] = k;
  // by height (then slot: a canonical order), so a query for a band of heights stops early
  for (std::size_t c = 0; c < columns; ++c)
    std::sort(by_column.begin() + column_start[c], by_column.begin() + column_start[c + 1],
              [&](std::uint32_t a, std::uint32_t b) {
                return x[a].z < x[b].z || (x[a].z == x[b].z && a < b);
              });
  ++revision;
}

std::string store_error(const Grains& hot, const StaticStore& statics, GrainId next_id,
                        std::int64_t expected) {
  const std::size_t n = hot.size(), ns = statics.size();
  for (std::size_t size : {hot.state.size(), hot.x.size(), hot.v.size(), hot.w.size(), hot.r.size(),
                           hot.m.size(), hot.inv_m.size(), hot.inv_I.size()})
    if (size != n)
      return fmt::format("the hot store's arrays differ in length ({} ids, {})", n, size);
  for (std::size_t size : {statics.x.size(), statics.r.size(), statics.column.size()})
    if (size != ns)
      return fmt::format("the static store's arrays differ in length ({} ids, {})", ns, size);
  std::vector<std::uint8_t> held(next_id, 0);  // 1: hot, 2: static
  for (std::size_t i = 0; i < n; ++i) {
    const GrainId id = hot.id[i];
    if (hot.state[i] == GrainState::Static)
      return fmt::format("grain {} is STATIC but in the hot store (slot {})", id, i);
    if (id >= next_id) return fmt::format("grain {} in the hot store: ids end at {}", id, next_id);
    if (held[id]) return fmt::format("grain {} is twice in the hot store", id);
    held[id] = 1;
  }
  for (std::size_t k = 0; k < ns; ++k) {
    const GrainId id = statics.id[k];
    if (id >= next_id)
      return fmt::format("grain {} in the static store: ids end at {}", id, next_id);
    if (held[id])
      return fmt::format("grain {} is in the static store and {}", id,
                         held[id] == 1 ? "in the hot store" : "twice in it");
    held[id] = 2;
  }
  if (static_cast<std::int64_t>(n + ns) != expected)
    return fmt::format("{} ACTIVE and INTERFACE grains and {} STATIC ones are {}, not {}", n, ns,
                       n + ns, expected);
  return {};
}

}  // namespace sandflow

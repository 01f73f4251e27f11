#include "dem/grains.hpp"

#include <algorithm>
#include <utility>

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

}  // namespace sandflow

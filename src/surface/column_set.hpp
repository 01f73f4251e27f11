// A set of height-field columns that costs what it holds: adding is O(1), listing and clearing
// are O(size), never O(columns). The surface flow keeps its work to the columns that can change
// (docs/design.md §4, "Only what can change"), so a bed of millions of grains at rest costs
// nothing per update; a flag per column (a byte each) is the only thing the set's size does not
// bound.
#pragma once

#include <cstdint>
#include <vector>

namespace sandflow {

class ColumnSet {
 public:
  explicit ColumnSet(std::size_t columns = 0) : in_(columns, 0) {}

  /// Sets the number of columns and empties the set.
  void resize(std::size_t columns) {
    in_.assign(columns, 0);
    list_.clear();
  }
  std::size_t columns() const { return in_.size(); }

  /// Adds column c; false when it was there already.
  bool add(std::uint32_t c) {
    if (in_[c]) return false;
    in_[c] = 1;
    list_.push_back(c);
    return true;
  }
  /// Adds every column (in ascending order after those already held).
  void add_all() {
    for (std::size_t c = 0; c < in_.size(); ++c) add(static_cast<std::uint32_t>(c));
  }
  void add(const std::vector<std::uint32_t>& cs) {
    for (std::uint32_t c : cs) add(c);
  }
  bool contains(std::size_t c) const { return in_[c] != 0; }
  bool empty() const { return list_.empty(); }
  std::size_t size() const { return list_.size(); }
  /// The columns held, in the order they joined.
  const std::vector<std::uint32_t>& list() const { return list_; }

  void clear() {
    for (std::uint32_t c : list_) in_[c] = 0;
    list_.clear();
  }

 private:
  std::vector<std::uint8_t> in_;
  std::vector<std::uint32_t> list_;
};

}  // namespace sandflow

// FNV-1a over raw bytes: the state hash that proves two runs are bit-for-bit the same.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace sandflow {

class Hasher {
 public:
  void add_bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) {
      h_ ^= p[i];
      h_ *= 0x100000001b3ULL;
    }
  }
  template <class T>
  void add(const T& v) { add_bytes(&v, sizeof(T)); }
  std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ULL;
};

}  // namespace sandflow

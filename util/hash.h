// A content hash that is the same across runs, compilers and machines (std::hash is not): FNV-1a,
// 64 bit. For cache keys and fingerprints, not for security.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace quijibo {

struct Fnv1a {
  std::uint64_t h = 0xcbf29ce484222325ull;
  // Adds `bytes` and a separator, so ("ab", "c") and ("a", "bc") differ.
  void add(std::string_view bytes) {
    for (unsigned char c : bytes) {
      h ^= c;
      h *= 0x100000001b3ull;
    }
    h ^= 0xff;
    h *= 0x100000001b3ull;
  }
  std::string hex() const {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
  }
};

}  // namespace quijibo

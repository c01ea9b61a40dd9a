// Little helpers for the binary .fpmap format, shared by the plan block (fploc/floorplan/io.h)
// and the ANNF block (fploc/annf): host-endian (little-endian on every supported target) PODs,
// length-prefixed strings and the FNV-1a checksum. Read errors throw "SOURCE: truncated map file".
#pragma once
#include <cstdint>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string>

namespace fploc::binary {

template <typename T>
void put(std::ostream& out, const T& v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <typename T>
T get(std::istream& in, const std::string& source) {
  T v{};
  in.read(reinterpret_cast<char*>(&v), sizeof(T));
  if (!in) throw std::runtime_error(source + ": truncated map file");
  return v;
}

inline void put_string(std::ostream& out, const std::string& s) {
  put<uint32_t>(out, uint32_t(s.size()));
  out.write(s.data(), std::streamsize(s.size()));
}

inline std::string get_string(std::istream& in, const std::string& source) {
  const uint32_t n = get<uint32_t>(in, source);
  if (n > (1u << 24)) throw std::runtime_error(source + ": corrupt map file (string length " + std::to_string(n) + ")");
  std::string s(n, '\0');
  in.read(s.data(), n);
  if (!in) throw std::runtime_error(source + ": truncated map file");
  return s;
}

inline uint64_t fnv1a(const void* data, size_t n, uint64_t h = 1469598103934665603ull) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

}  // namespace fploc::binary

// A bounded cursor over one serialized message: ROS 1 (little-endian, packed, strings without NUL) or
// CDR (4-byte encapsulation header; each primitive aligned to its size, at most 8, from the end of the
// header; strings count their NUL). Reading past the end sets ok = false and the name of the field.
#pragma once
#include <cstring>
#include <vector>
#include <string>
#include <type_traits>

#include "fploc/recording/recording.h"

namespace fploc::rec {

class Wire {
 public:
  Wire(const uint8_t* d, size_t n, Encoding e) : d_(d), n_(n), cdr_(e == Encoding::kCdr) {
    if (cdr_) {
      if (n < 4) {
        bad("CDR encapsulation header");
        return;
      }
      // 0x0000 CDR_BE, 0x0001 CDR_LE (also PL_CDR 2/3 and XCDR2 variants: the low bit is the endianness).
      if (d[0] != 0 || d[1] > 0x0b) {
        bad("CDR encapsulation header");
        return;
      }
      swap_ = (d[1] & 1) == 0;
      d_ += 4;
      n_ -= 4;
    }
  }
  bool ok() const { return ok_; }
  const char* failed_field() const { return field_; }
  void field(const char* f) { cur_ = f; }

  template <class T>
  T get() {
    static_assert(std::is_arithmetic_v<T>);
    align(sizeof(T) > 8 ? 8 : sizeof(T));
    if (!ok_ || n_ - i_ < sizeof(T)) return bad(cur_), T{};
    T v;
    if (swap_ && sizeof(T) > 1) {
      uint8_t b[sizeof(T)];
      for (size_t k = 0; k < sizeof(T); ++k) b[k] = d_[i_ + sizeof(T) - 1 - k];
      std::memcpy(&v, b, sizeof v);
    } else {
      std::memcpy(&v, d_ + i_, sizeof v);
    }
    i_ += sizeof(T);
    return v;
  }
  std::string str() {
    uint32_t len = get<uint32_t>();
    if (!ok_ || len > n_ - i_) return bad(cur_), std::string();
    const size_t at = i_;
    i_ += len;
    if (cdr_) {
      if (len == 0) return std::string();  // tolerated: some writers send 0 for ""
      --len;                                // the terminating NUL
    }
    return std::string(reinterpret_cast<const char*>(d_ + at), len);
  }
  // A sequence's element count, checked against what is left (each element takes >= min_size bytes).
  uint32_t count(size_t min_size) {
    const uint32_t c = get<uint32_t>();
    if (ok_ && min_size > 0 && c > (n_ - i_) / min_size) return bad(cur_), 0;
    return c;
  }
  // The bytes of a float32[] of c elements (after its count), in the message's byte order; nullptr
  // (and not ok) when they run past the end.
  const uint8_t* float_bytes(uint32_t c) {
    align(4);
    if (!ok_ || c > (n_ - i_) / 4) return bad(cur_), nullptr;
    const uint8_t* p = d_ + i_;
    i_ += size_t(c) * 4;
    return p;
  }
  // Raw bytes of a uint8[] (after its count).
  const uint8_t* bytes(size_t len) {
    if (!ok_ || len > n_ - i_) return bad(cur_), nullptr;
    const uint8_t* p = d_ + i_;
    i_ += len;
    return p;
  }
  bool cdr() const { return cdr_; }
  bool big_endian() const { return swap_; }

 private:
  void align(size_t a) {
    if (!cdr_ || !ok_) return;
    const size_t pad = (a - i_ % a) % a;
    if (pad > n_ - i_) return bad(cur_);
    i_ += pad;
  }
  void bad(const char* f) {
    if (ok_) field_ = f;
    ok_ = false;
  }
  const uint8_t* d_;
  size_t n_, i_ = 0;
  bool cdr_, swap_ = false, ok_ = true;
  const char* cur_ = "message";
  const char* field_ = "";
};

}  // namespace fploc::rec

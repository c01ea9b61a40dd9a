#include "fploc/recording/decompress.h"

#include <bzlib.h>
#include <lz4frame.h>
#include <zstd.h>

namespace fploc::rec {

std::string decompress(const std::string& method, const uint8_t* in, size_t n, size_t expected,
                       std::vector<uint8_t>& out) {
  if (expected > (size_t(1) << 32)) return "uncompressed size " + std::to_string(expected) + " B is implausible";
  out.resize(expected);
  if (method == "bz2") {
    if (n > 0xFFFFFFFFu) return "bz2 chunk too large";
    unsigned int len = unsigned(expected);
    const int rc = BZ2_bzBuffToBuffDecompress(reinterpret_cast<char*>(out.data()), &len,
                                              const_cast<char*>(reinterpret_cast<const char*>(in)), unsigned(n), 0, 0);
    if (rc != BZ_OK) {
      const char* what = rc == BZ_DATA_ERROR         ? "BZ_DATA_ERROR: the compressed data is corrupt"
                         : rc == BZ_DATA_ERROR_MAGIC ? "BZ_DATA_ERROR_MAGIC: not bz2 data (no 'BZh' header)"
                         : rc == BZ_UNEXPECTED_EOF   ? "BZ_UNEXPECTED_EOF: the compressed data ends too early"
                         : rc == BZ_OUTBUFF_FULL     ? "BZ_OUTBUFF_FULL: larger than the size field"
                         : rc == BZ_MEM_ERROR        ? "BZ_MEM_ERROR: out of memory"
                                                     : "see bzlib.h";
      return "bz2 error " + std::to_string(rc) + " (" + what + ")";
    }
    if (len != expected) return "bz2 gave " + std::to_string(len) + " B, size field says " + std::to_string(expected);
    return "";
  }
  if (method == "lz4") {
    LZ4F_dctx* ctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION))) return "lz4: no context";
    size_t src_pos = 0, dst_pos = 0, hint = 1;
    std::string err;
    while (src_pos < n && hint != 0) {
      size_t src_len = n - src_pos, dst_len = expected - dst_pos;
      hint = LZ4F_decompress(ctx, out.data() + dst_pos, &dst_len, in + src_pos, &src_len, nullptr);
      if (LZ4F_isError(hint)) {
        err = std::string("lz4: ") + LZ4F_getErrorName(hint);
        break;
      }
      src_pos += src_len;
      dst_pos += dst_len;
      if (src_len == 0 && dst_len == 0) {
        err = "lz4: larger than the size field";
        break;
      }
    }
    LZ4F_freeDecompressionContext(ctx);
    if (!err.empty()) return err;
    if (hint != 0) return "lz4: frame truncated";
    if (dst_pos != expected) return "lz4 gave " + std::to_string(dst_pos) + " B, size field says " + std::to_string(expected);
    return "";
  }
  if (method == "zstd") {
    const size_t r = ZSTD_decompress(out.data(), expected, in, n);
    if (ZSTD_isError(r)) return std::string("zstd: ") + ZSTD_getErrorName(r);
    if (r != expected) return "zstd gave " + std::to_string(r) + " B, size field says " + std::to_string(expected);
    return "";
  }
  std::string name;  // the name from the file, printable (a damaged one holds any bytes)
  for (const char ch : method) {
    const auto u = uint8_t(ch);
    static const char* hex = "0123456789abcdef";
    if (u >= 0x20 && u < 0x7F && ch != '\\') name += ch;
    else name += std::string("\\x") + hex[u >> 4] + hex[u & 15];
  }
  return "unsupported compression '" + name + "'";
}

std::vector<uint8_t> compress(const std::string& method, const uint8_t* in, size_t n) {
  std::vector<uint8_t> out;
  if (method == "bz2") {
    unsigned int len = unsigned(n + n / 100 + 600);
    out.resize(len);
    if (BZ2_bzBuffToBuffCompress(reinterpret_cast<char*>(out.data()), &len,
                                 const_cast<char*>(reinterpret_cast<const char*>(in)), unsigned(n), 9, 0, 0) != BZ_OK)
      return {};
    out.resize(len);
  } else if (method == "lz4") {
    out.resize(LZ4F_compressFrameBound(n, nullptr));
    const size_t r = LZ4F_compressFrame(out.data(), out.size(), in, n, nullptr);
    if (LZ4F_isError(r)) return {};
    out.resize(r);
  } else if (method == "zstd") {
    out.resize(ZSTD_compressBound(n));
    const size_t r = ZSTD_compress(out.data(), out.size(), in, n, 3);
    if (ZSTD_isError(r)) return {};
    out.resize(r);
  } else {
    out.assign(in, in + n);
  }
  return out;
}

}  // namespace fploc::rec

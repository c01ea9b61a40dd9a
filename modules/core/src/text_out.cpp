#include "fploc/core/text_out.h"

#include <cstdint>
#include <nlohmann/json.hpp>

namespace fploc {
namespace {

// Length of the valid UTF-8 sequence at s[i] (1..4), 0 when the bytes there are not one (a lone continuation
// byte, a cut sequence, an overlong form, a surrogate, above U+10FFFF).
size_t utf8_len(std::string_view s, size_t i) {
  const auto b = [&](size_t k) { return uint8_t(s[i + k]); };
  const uint8_t c = b(0);
  if (c < 0x80) return 1;
  size_t n = 0;
  uint32_t cp = 0;
  if (c >= 0xC2 && c <= 0xDF) n = 2, cp = c & 0x1F;
  else if (c >= 0xE0 && c <= 0xEF) n = 3, cp = c & 0x0F;
  else if (c >= 0xF0 && c <= 0xF4) n = 4, cp = c & 0x07;
  else return 0;
  if (s.size() - i < n) return 0;
  for (size_t k = 1; k < n; ++k) {
    if ((b(k) & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (b(k) & 0x3F);
  }
  if ((n == 3 && cp < 0x800) || (n == 4 && cp < 0x10000) || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
  return n;
}

void hex(std::string& out, uint8_t u) {
  static const char* digits = "0123456789abcdef";
  out += "\\x";
  out += digits[u >> 4];
  out += digits[u & 15];
}

}  // namespace

std::string printable(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (size_t i = 0; i < s.size();) {
    const auto u = uint8_t(s[i]);
    const size_t n = utf8_len(s, i);
    const bool c1 = n == 2 && u == 0xC2 && uint8_t(s[i + 1]) < 0xA0;  // U+0080..U+009F (0x9B: the 8-bit CSI)
    if (n == 0 || u < 0x20 || u == 0x7F || u == '\\') {
      hex(out, u);
      ++i;
    } else if (c1) {
      hex(out, u);
      hex(out, uint8_t(s[i + 1]));
      i += 2;
    } else {
      out.append(s.substr(i, n));
      i += n;
    }
  }
  return out;
}

std::string json_text(const nlohmann::json& j, int indent) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string xml_text(std::string_view s) {
  std::string o;
  o.reserve(s.size());
  for (const char c : s) {
    if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '&') o += "&amp;";
    else if (c == '"') o += "&quot;";
    else o += c;
  }
  return o;
}

}  // namespace fploc

#include "io/load_error.h"

#include <cstdint>
#include <cstdio>

namespace caustica {

namespace {

// Length of the valid UTF-8 sequence at text[i] that is printable (not a C1 control, not an
// overlong form or a surrogate), or 0.
size_t printable_utf8_length(std::string_view text, size_t i) {
  const auto byte = [&](size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b = byte(i);
  size_t n;
  uint32_t cp;
  if (b >= 0xC2 && b <= 0xDF) {
    n = 2, cp = b & 0x1F;
  } else if (b >= 0xE0 && b <= 0xEF) {
    n = 3, cp = b & 0x0F;
  } else if (b >= 0xF0 && b <= 0xF4) {
    n = 4, cp = b & 0x07;
  } else {
    return 0;
  }
  if (i + n > text.size()) return 0;
  for (size_t k = 1; k < n; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (byte(i + k) & 0x3F);
  }
  const uint32_t min_cp[5] = {0, 0, 0x80, 0x800, 0x10000};
  if (cp < min_cp[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
  if (cp < 0xA0) return 0;  // C1 controls (U+0080..U+009F): CSI and friends
  return n;
}

// Appends text[i...] (one byte or one UTF-8 sequence) escaped; returns the bytes consumed.
size_t append_escaped(std::string& out, std::string_view text, size_t i, bool in_quotes) {
  const unsigned char c = static_cast<unsigned char>(text[i]);
  if (c >= 0x20 && c < 0x7F) {
    if (in_quotes && (c == '"' || c == '\\')) out += '\\';
    out += char(c);
    return 1;
  }
  if (const size_t n = c >= 0x80 ? printable_utf8_length(text, i) : 0) {
    out.append(text.substr(i, n));
    return n;
  }
  char hex[5];
  std::snprintf(hex, sizeof(hex), "\\x%02X", c);
  out += hex;
  return 1;
}

}  // namespace

std::string format_number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

std::string escape_text(std::string_view text) {
  std::string out;
  for (size_t i = 0; i < text.size();) i += append_escaped(out, text, i, false);
  return out;
}

std::string quote_excerpt(std::string_view text, size_t max_bytes) {
  std::string out = "\"";
  size_t i = 0;
  while (i < text.size() && i < max_bytes) i += append_escaped(out, text, i, true);
  if (i < text.size()) out += "...";
  out += '"';
  return out;
}

}  // namespace caustica

#include "report/html.hpp"

#include <cstdint>

namespace sandflow {

std::string html_escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string base64_encode(std::string_view bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t k = 0;
  // whole groups of three bytes -> four characters
  for (; k + 3 <= bytes.size(); k += 3) {
    const std::uint32_t v = std::uint32_t(static_cast<unsigned char>(bytes[k])) << 16 |
                            std::uint32_t(static_cast<unsigned char>(bytes[k + 1])) << 8 |
                            std::uint32_t(static_cast<unsigned char>(bytes[k + 2]));
    out += kAlphabet[v >> 18 & 63];
    out += kAlphabet[v >> 12 & 63];
    out += kAlphabet[v >> 6 & 63];
    out += kAlphabet[v & 63];
  }
  // one or two bytes left: padded with '='
  const std::size_t rest = bytes.size() - k;
  if (rest > 0) {
    std::uint32_t v = std::uint32_t(static_cast<unsigned char>(bytes[k])) << 16;
    if (rest == 2) v |= std::uint32_t(static_cast<unsigned char>(bytes[k + 1])) << 8;
    out += kAlphabet[v >> 18 & 63];
    out += kAlphabet[v >> 12 & 63];
    out += rest == 2 ? kAlphabet[v >> 6 & 63] : '=';
    out += '=';
  }
  return out;
}

}  // namespace sandflow

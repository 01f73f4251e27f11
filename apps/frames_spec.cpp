#include "frames_spec.hpp"

#include <charconv>
#include <string_view>
#include <system_error>
#include <vector>

#include <fmt/format.h>

#include "core/error.hpp"

namespace sandflow {

FramesSpec parse_frames(const std::string& text, bool with_step) {
  const std::string forms =
      with_step ? "expected N, A:B, A:, :B, all or :, or every K-th of them, A:B:K (frames count "
                  "from 1)"
                : "expected N, A:B, A:, :B, all or : (frames count from 1)";
  const auto bad = [&](const std::string& why) {
    throw InputError(fmt::format("--frames {}: {}", text, why));
  };
  const auto number = [&](std::string_view s, const char* what) -> std::optional<int> {
    if (s.empty()) return std::nullopt;
    int v = 0;
    const auto res = std::from_chars(s.data(), s.data() + s.size(), v);
    if (res.ec == std::errc::result_out_of_range) bad(fmt::format("{} is too large", s));
    if (res.ec != std::errc() || res.ptr != s.data() + s.size())
      bad(fmt::format("\"{}\" is not a {}; {}", s, what, forms));
    if (v < 1)
      bad(std::string_view(what) == "step"
              ? fmt::format("a step of {}: a step is at least 1", v)
              : fmt::format("frame {} does not exist: frames count from 1", v));
    return v;
  };
  if (text == "all" || text == ":") return {};
  if (text.empty()) bad(forms);
  std::vector<std::string_view> parts;
  for (std::size_t at = 0;;) {
    const std::size_t colon = text.find(':', at);
    parts.push_back(std::string_view(text).substr(at, colon - at));
    if (colon == std::string::npos) break;
    at = colon + 1;
  }
  if (parts.size() == 1) {
    const auto n = number(parts[0], "frame number");
    return {n, n};
  }
  if (parts.size() > (with_step ? 3u : 2u)) bad(forms);
  FramesSpec spec{number(parts[0], "frame number"), number(parts[1], "frame number")};
  if (parts.size() == 3) {
    const auto k = number(parts[2], "step");
    if (!k) bad(forms);
    spec.step = *k;
  }
  if (spec.first && spec.last && *spec.last < *spec.first)
    bad(fmt::format("the last frame {} comes before the first {}: expected A:B with A <= B",
                    *spec.last, *spec.first));
  return spec;
}

}  // namespace sandflow

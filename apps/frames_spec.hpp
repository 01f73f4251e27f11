// Which frames of a run a command takes (--frames of `render` and `measure`): N, A:B (inclusive),
// A:, :B, all (or :), and for `measure` every K-th of a range, A:B:K.
#pragma once

#include <optional>
#include <string>

namespace sandflow {

/// --frames as written: either end may be open (A:, :B, all); every `step`-th frame from the first.
struct FramesSpec {
  std::optional<int> first, last;
  int step = 1;
};

/// Parses --frames; `with_step` allows A:B:K. Throws InputError naming the option and the forms.
FramesSpec parse_frames(const std::string& text, bool with_step = false);

}  // namespace sandflow

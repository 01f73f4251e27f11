// The scene loader's reader of one TOML table (internal to src/scene/): TableReader reads a table
// key by key, converting each value and checking its range, and reports anything wrong as an
// InputError placed at "PATH:LINE:COL" (or "--set KEY"); with it, the pieces its messages are made
// of (Range, Places, the text of a value).
//
// Each read() names one key, converts it and checks its range; the keys a table reads are, by
// construction, the keys it accepts, so finish() reports any other key (pbrt rejects unused
// parameters) and lists the accepted ones. A [[geometry]] or [[emitter]] table reads only the keys
// of its type, so a key of another type is reported the same way: "geometry[1].radius is not a
// key of a plane (keys: ...)".
#pragma once

#include <toml++/toml.h>

#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "config/scene_config.hpp"
#include "core/vec3.hpp"

namespace sandflow::loader {

inline constexpr Real kInf = std::numeric_limits<Real>::infinity();

// ---- Text for messages --------------------------------------------------------------------------

/// The shortest text that reads back as `v`; "nan", "inf", "-inf".
std::string format_real(Real v);
/// A whole number as digits (1e5 -> "100000"), a huge or non-finite one as format_real() has it.
std::string format_count(Real v);
/// "a string", "an integer", "a table", ...
std::string type_name(const toml::node& n);
/// "word" with quotes.
std::string in_quotes(std::string_view s);
/// A scalar as the user wrote it (near enough): 1.4, 7, "dem", true.
std::string value_text(const toml::node& n);
std::string join(const std::vector<std::string>& items, std::string_view sep);

// ---- Ranges -------------------------------------------------------------------------------------

/// An interval a value must lie in; it describes itself in messages ("is outside (0, 1]").
struct Range {
  Real lo = -kInf;
  Real hi = kInf;
  bool lo_open = false;
  bool hi_open = false;

  bool contains(Real v) const {
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }

  /// What is wrong with a value outside the range; integral ranges print their bounds exactly.
  std::string violation(bool integral) const;
};

inline constexpr Range kAny{};
inline constexpr Range kPositive{0, kInf, true, false};
inline constexpr Range kNonNegative{0, kInf, false, false};
constexpr Range closed(Real lo, Real hi) {
  return {lo, hi, false, false};
}
constexpr Range open_closed(Real lo, Real hi) {
  return {lo, hi, true, false};
}
constexpr Range open(Real lo, Real hi) {
  return {lo, hi, true, true};
}

/// One word of a fixed set and the value it stands for: {"dem", Mode::Dem}.
template <class E>
using Choices = std::pair<std::string_view, E>;

// ---- Places -------------------------------------------------------------------------------------

/// Where a node came from: "PATH:LINE:COL" in the scene file, or "--set KEY" for an override
/// (override values are parsed with that text as their source path).
class Places {
 public:
  /// `record`, when given, collects the place of every key read (SceneConfig::key_places).
  explicit Places(std::string file, SceneConfig* record = nullptr)
      : file_(std::move(file)), record_(record) {}

  /// Notes where the key named `name` (as messages name it) was read from.
  void note(const std::string& name, const toml::key& key, const toml::node& value) const;
  /// Adds "PLACE: what" to the scene's warnings.
  void warn(const std::string& place, const std::string& what) const;

  std::string of(const toml::source_region& src) const;
  /// A key = value pair is placed at the key, unless an override supplied the value.
  std::string of(const toml::key& key, const toml::node& value) const;

  bool is_override(const toml::source_region& src) const { return src.path && *src.path != file_; }

 private:
  std::string file_;
  SceneConfig* record_;
};

/// Throws InputError("PLACE: WHAT").
[[noreturn]] void fail(const std::string& place, const std::string& what);

/// A key as a message may show it: a NUL or a control character is written \uXXXX.
std::string printable(std::string_view key);

// ---- Reading one table --------------------------------------------------------------------------

class TableReader {
 public:
  /// `prefix` names the table in messages: "material", "geometry[2]", "" for the document root.
  TableReader(const Places& places, const toml::table& table, std::string prefix)
      : places_(places), table_(table), prefix_(std::move(prefix)) {}

  /// The key as messages name it: "material.friction".
  std::string name(std::string_view key) const;

  void read(std::string_view key, Real& out, Range range = kAny);
  void read(std::string_view key, std::optional<Real>& out, Range range = kAny);

  /// Integers; a float with an integral value (count = 1e6) is taken too.
  template <std::integral T>
  requires(!std::same_as<T, bool>) void read(std::string_view key, T& out, Range range = kAny) {
    const auto e = find(key);
    if (!e) return;
    const std::int64_t v = integer(*e, name(key), range);
    if (!std::in_range<T>(v))
      fail(place(*e), name(key) + " = " + std::to_string(v) + " is too large (at most " +
                          std::to_string(std::numeric_limits<T>::max()) + ")");
    out = static_cast<T>(v);
  }

  void read(std::string_view key, bool& out);
  void read(std::string_view key, std::string& out);
  /// A name: one line of printable text (it goes into the comments and headers of exported files,
  /// where a line break or a control character would end the comment and start code).
  void read_name(std::string_view key, std::string& out);

  /// An array of strings, each with the place it came from (for messages about one of them).
  struct Word {
    std::string text, place, name;
  };
  void read(std::string_view key, std::optional<std::vector<Word>>& out);

  /// A vector: an array of exactly 3 finite numbers. Only the first `checked` components are
  /// held to `range` (a pour rectangle has x, y extents and an unused z).
  void read(std::string_view key, Vec3& out, Range range = kAny, int checked = 3);

  /// A fixed number of finite numbers, [x0, y0, x1, y1]; unset when the table lacks the key.
  template <std::size_t N>
  void read(std::string_view key, std::optional<std::array<Real, N>>& out, Range range = kAny) {
    if (const auto e = find(key)) out = numbers<N>(*e, name(key), range, static_cast<int>(N));
  }

  /// A grid of heights: an array of at least 2 rows of the same length (at least 2 finite
  /// numbers each), at most max_side rows and max_side numbers a row; sizes are checked before
  /// anything is allocated.
  void read(std::string_view key, HeightGrid& out, int max_side);

  /// One of a fixed set of words: mode = "surface" | "dem".
  template <class E, std::size_t N>
  void read(std::string_view key, E& out, const Choices<E> (&choices)[N]) {
    const auto e = find(key);
    if (!e) return;
    std::vector<std::string> words;
    for (const auto& [word, value] : choices) words.push_back(in_quotes(word));
    const auto* s = e->node->as_string();
    if (!s)
      fail(place(*e),
           name(key) + ": expected one of " + join(words, ", ") + ", got " + type_name(*e->node));
    for (const auto& [word, value] : choices) {
      if (s->get() == word) {
        out = value;
        return;
      }
    }
    fail(place(*e),
         name(key) + " = " + value_text(*e->node) + " is not one of " + join(words, ", "));
  }

  /// A sub-table ([material]), or nullptr when the document has none.
  const toml::table* table(std::string_view key);
  /// An array of tables ([[emitter]]), or nullptr when the document has none.
  const toml::array* array_of_tables(std::string_view key);

  bool has(std::string_view key) const { return table_.contains(key); }

  /// A reader of the sub-table `key` = {...} of this table, named "prefix.key" in messages.
  TableReader nested(std::string_view key, const toml::table& t) const {
    return {places_, t, name(key)};
  }

  /// Where `key` is in the file (or the --set that gave it), else where the table is.
  std::string place_at(std::string_view key) const;
  /// Fails at `key` if the table has it, else at the table itself.
  [[noreturn]] void fail_at(std::string_view key, const std::string& what) const;
  /// A warning at `key` (which the table has).
  void warn_at(std::string_view key, const std::string& what) const;
  /// The table has `key` from the scene file itself, not from a --set.
  bool in_file(std::string_view key) const;

  void require(std::string_view key, std::string_view expected) const;

  /// Every key of the table must have been read; `what` names the table ("[material]", "a
  /// plane"). The earliest offending key in the file is reported.
  void finish(std::string_view what) const;

 private:
  struct Entry {
    const toml::key* key;
    const toml::node* node;
  };

  /// Looks a key up; asking for it also makes it a key this table accepts.
  std::optional<Entry> find(std::string_view key);

  std::string place(const Entry& e) const { return places_.of(*e.key, *e.node); }

  /// An integer (or a float with an integral value) inside `range`.
  std::int64_t integer(const Entry& e, const std::string& n, Range range) const;

  /// An array of exactly N finite numbers; only the first `checked` are held to `range`.
  template <std::size_t N>
  std::array<Real, N> numbers(const Entry& e, const std::string& n, Range range,
                              int checked) const {
    const toml::array& a = array_of(e, n, N);
    std::array<Real, N> out{};
    for (std::size_t i = 0; i < N; ++i) {
      const toml::node& c = *a.get(i);
      out[i] = number(c, n + "[" + std::to_string(i) + "]", places_.of(c.source()),
                      static_cast<int>(i) < checked ? range : kAny);
    }
    return out;
  }

  /// The entry's array, which must have exactly `size` elements.
  const toml::array& array_of(const Entry& e, const std::string& n, std::size_t size) const;

  /// A finite number (integers accepted) inside `range`.
  static Real number(const toml::node& n, const std::string& name, const std::string& place,
                     Range range);

  const Places& places_;
  const toml::table& table_;
  std::string prefix_;
  std::vector<std::string> known_;  ///< keys read so far, in the order the loader asks for them
};

}  // namespace sandflow::loader

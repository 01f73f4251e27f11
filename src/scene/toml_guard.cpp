// The guard in front of toml++ (toml_guard.hpp): a pre-lexer that finds what Debian's toml++ 3.3
// cannot be given safely, before it sees the text:
// - It recurses once per level of table nesting when it finishes a document, so a dotted key of
//   100,000 parts (a.a.a...) overflows the stack. It caps the nesting of inline tables and arrays
//   itself (256 levels); the parts of a dotted key or table name are capped here, so no document
//   nests deeper than about 256 x 16 levels.
// - Its test for Unicode whitespace reaches __builtin_unreachable() for most non-ASCII characters
//   (upstream issues 190 and 295, undefined behaviour), and it makes that test on characters
//   outside strings and comments (even inside a malformed value: 1'Z'), and after a backslash in
//   a """multi-line string""". TOML allows non-ASCII characters only in strings and comments, so
//   the first is an error anyway; the second is refused too.
// toml_hazard() follows TOML's grammar far enough to know where a string may start: at the start
// of a key, a table name or a value, never inside another token. A text it misreads is one
// toml++ refuses at or before that point, so a character it takes for part of a string is one
// toml++ reads as such or never reads.

#include "scene/toml_guard.hpp"

#include <cctype>
#include <utility>
#include <vector>

namespace sandflow::loader {
namespace {

constexpr int kMaxKeyParts = 16;

bool key_char(char ch) {
  return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-';
}
// bare values: numbers, dates, true, inf, nan
bool value_char(char ch) {
  return key_char(ch) || ch == '+' || ch == '.' || ch == ':';
}
bool ascii(char ch) {
  return static_cast<unsigned char>(ch) < 0x80;
}

// One pass over a text, token by token, keeping what the grammar expects next.
class HazardScan {
 public:
  explicit HazardScan(std::string_view text) : text_(text) {}

  std::optional<TomlHazard> run() {
    while (i_ < text_.size())
      if (auto h = step()) return h;
    return std::nullopt;
  }

 private:
  // What the grammar expects next: a key (at a line's start, after '{' or ',' in an inline
  // table, after a key's '.'), a table name (after '[' at a line's start, after its '.'), a value
  // (after '=', '[' or ',' in an array), or nothing a string may start (Other).
  enum class Expect { Key, KeyPart, Table, TablePart, Value, Other };
  enum class Open { Array, InlineTable };

  TomlHazard hazard(std::size_t at, std::string what) const {
    return TomlHazard{line_, at - line_start_ + 1, std::move(what)};
  }

  bool key_like() const { return expect_ == Expect::Key || expect_ == Expect::Table; }

  // One token, or one character between tokens, from i_.
  std::optional<TomlHazard> step() {
    const std::size_t at = i_;
    const char ch = text_[i_];
    if (ch == '\n') {
      ++line_;
      line_start_ = ++i_;
      if (open_.empty()) {
        expect_ = Expect::Key;
        parts_ = 0;
      }
    } else if (ch == ' ' || ch == '\t' || ch == '\r') {
      ++i_;
    } else if (ch == '#') {
      while (i_ < text_.size() && text_[i_] != '\n') ++i_;
    } else if (!ascii(ch)) {
      return hazard(at,
                    "a non-ASCII character outside a string or comment: TOML allows them "
                    "only in \"strings\" and # comments");
    } else if (ch == '"' || ch == '\'') {
      return quote(ch);
    } else if (key_like() && key_char(ch)) {
      while (i_ < text_.size() && key_char(text_[i_])) ++i_;
      if (auto h = part(at)) return h;
      expect_ = expect_ == Expect::Key ? Expect::KeyPart : Expect::TablePart;
    } else if (value_char(ch) &&
               !(ch == '.' && (expect_ == Expect::KeyPart || expect_ == Expect::TablePart))) {
      while (i_ < text_.size() && value_char(text_[i_])) ++i_;
      expect_ = Expect::Other;
    } else {
      ++i_;
      punctuation(ch);
    }
    return std::nullopt;
  }

  // A quote at i_: a string where one may start (a key, a part of a table name, a value).
  std::optional<TomlHazard> quote(char ch) {
    const std::size_t at = i_;
    if (!key_like() && expect_ != Expect::Value) {
      expect_ = Expect::Other;  // not where a string may start: toml++ refuses it
      ++i_;
      return std::nullopt;
    }
    if (auto h = skip_string(ch)) return h;
    if (key_like())
      if (auto h = part(at)) return h;
    expect_ = expect_ == Expect::Key     ? Expect::KeyPart
              : expect_ == Expect::Table ? Expect::TablePart
                                         : Expect::Other;
    return std::nullopt;
  }

  // Skips a string opened at i_ by `quote`, by TOML's rules (escapes only in "basic" strings; a
  // multi-line string's closing triple may be followed by one or two quotes of its content).
  std::optional<TomlHazard> skip_string(char quote) {
    const std::string triple(3, quote);
    const bool multi = text_.substr(i_, 3) == triple;
    i_ += multi ? 3 : 1;
    while (i_ < text_.size()) {
      const char ch = text_[i_];
      if (ch == '\\' && quote == '"' && multi) {
        if (auto h = multi_line_backslash()) return h;
      } else if (ch == '\\' && quote == '"') {
        i_ += text_.substr(i_ + 1, 1) == "\n" ? 1 : 2;
      } else if (ch == '\n') {
        if (!multi) return std::nullopt;  // an unterminated string: toml++ reports it
        ++line_;
        line_start_ = ++i_;
      } else if (ch != quote) {
        ++i_;
      } else if (!multi) {
        ++i_;
        return std::nullopt;
      } else if (text_.substr(i_, 3) == triple) {
        i_ += 3;
        for (int extra = 0; extra < 2 && i_ < text_.size() && text_[i_] == quote; ++extra) ++i_;
        return std::nullopt;
      } else {
        ++i_;
      }
    }
    return std::nullopt;
  }

  // A backslash at i_ in a """multi-line string""": an escape, or a line-ending backslash that
  // trims the whitespace after it.
  std::optional<TomlHazard> multi_line_backslash() {
    std::size_t j = i_ + 1;
    while (j < text_.size() &&
           (text_[j] == ' ' || text_[j] == '\t' || text_[j] == '\r' || text_[j] == '\n')) {
      if (text_[j] == '\n') {
        ++line_;
        line_start_ = j + 1;
      }
      ++j;
    }
    if (j < text_.size() && !ascii(text_[j]))
      return hazard(j,
                    "a non-ASCII character after a backslash in a multi-line string, "
                    "which the TOML library cannot read safely: write it as \\uXXXX");
    i_ = j == i_ + 1 ? i_ + 2 : j;
    return std::nullopt;
  }

  // One more part of a key or table name, starting at `at`.
  std::optional<TomlHazard> part(std::size_t at) {
    if (++parts_ > kMaxKeyParts)
      return hazard(at, "a dotted key or table name of more than " + std::to_string(kMaxKeyParts) +
                            " parts: expected at most " + std::to_string(kMaxKeyParts));
    return std::nullopt;
  }

  // A character of TOML's punctuation (or one toml++ refuses), already passed.
  void punctuation(char ch) {
    const bool in_array = !open_.empty() && open_.back() == Open::Array;
    const bool in_table = !open_.empty() && open_.back() == Open::InlineTable;
    if (ch == '.' && expect_ == Expect::KeyPart) {
      expect_ = Expect::Key;
    } else if (ch == '.' && expect_ == Expect::TablePart) {
      expect_ = Expect::Table;
    } else if (ch == '=' && expect_ == Expect::KeyPart) {
      expect_ = Expect::Value;
    } else if (ch == '[' && expect_ == Expect::Key && open_.empty() && parts_ == 0) {
      expect_ = Expect::Table;  // [table] or [[array of tables]]
    } else if (ch == '[' && expect_ == Expect::Table && parts_ == 0) {
      // the second '[' of [[
    } else if (ch == '[' && expect_ == Expect::Value) {
      open_.push_back(Open::Array);
    } else if (ch == '{' && expect_ == Expect::Value) {
      open_.push_back(Open::InlineTable);
      expect_ = Expect::Key;
      parts_ = 0;
    } else if (ch == ']' && in_array && expect_ != Expect::TablePart) {
      open_.pop_back();
      expect_ = Expect::Other;
    } else if (ch == '}' && in_table) {
      open_.pop_back();
      expect_ = Expect::Other;
    } else if (ch == ',' && in_array) {
      expect_ = Expect::Value;
    } else if (ch == ',' && in_table) {
      expect_ = Expect::Key;
      parts_ = 0;
    } else {
      expect_ = Expect::Other;
    }
  }

  std::string_view text_;
  std::size_t i_ = 0, line_ = 1, line_start_ = 0;
  Expect expect_ = Expect::Key;
  std::vector<Open> open_;  // the arrays and inline tables around i_
  int parts_ = 0;           // parts of the key or table name being read
};

}  // namespace

std::optional<TomlHazard> toml_hazard(std::string_view text) {
  return HazardScan(text).run();
}

}  // namespace sandflow::loader

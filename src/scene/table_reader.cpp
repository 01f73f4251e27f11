// TableReader (table_reader.hpp): reading one TOML table of a scene key by key, with the text of
// its messages.

#include "scene/table_reader.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>

#include "core/error.hpp"

namespace sandflow::loader {

// ---- Text for messages --------------------------------------------------------------------------

std::string format_real(Real v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);  // shortest round-trip form
  return std::string(buf, res.ptr);
}

std::string format_count(Real v) {
  return std::abs(v) < 9e18 ? std::to_string(static_cast<long long>(v)) : format_real(v);
}

std::string type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a float";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::table:
      return "a table";
    case toml::node_type::date:
      return "a date";
    case toml::node_type::time:
      return "a time";
    case toml::node_type::date_time:
      return "a date-time";
    case toml::node_type::none:
      break;
  }
  return "nothing";
}

// Built by appending: GCC 12 warns falsely (-Wrestrict) on "\"" + s + "\"".
std::string in_quotes(std::string_view s) {
  std::string out;
  out.reserve(s.size() + 2);
  out += '"';
  out += s;
  out += '"';
  return out;
}

std::string value_text(const toml::node& n) {
  if (const auto* i = n.as_integer()) return std::to_string(i->get());
  if (const auto* f = n.as_floating_point()) return format_real(f->get());
  if (const auto* s = n.as_string()) return in_quotes(s->get());
  if (const auto* b = n.as_boolean()) return b->get() ? "true" : "false";
  return type_name(n);
}

std::string join(const std::vector<std::string>& items, std::string_view sep) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : std::string(sep)) + s;
  return out;
}

// ---- Ranges -------------------------------------------------------------------------------------

std::string Range::violation(bool integral) const {
  const auto bound = [integral](Real b) {
    return integral && std::abs(b) < 9e18 ? std::to_string(static_cast<long long>(b))
                                          : format_real(b);
  };
  if (hi == kInf) return std::string("is not ") + (lo_open ? "> " : ">= ") + bound(lo);
  if (lo == -kInf) return std::string("is not ") + (hi_open ? "< " : "<= ") + bound(hi);
  return "is outside " + std::string(lo_open ? "(" : "[") + bound(lo) + ", " + bound(hi) +
         (hi_open ? ")" : "]");
}

// ---- Places -------------------------------------------------------------------------------------

std::string Places::of(const toml::source_region& src) const {
  if (is_override(src)) return *src.path;
  if (src.begin.line == 0) return file_;
  return file_ + ":" + std::to_string(src.begin.line) + ":" + std::to_string(src.begin.column);
}

std::string Places::of(const toml::key& key, const toml::node& value) const {
  if (is_override(value.source()) || key.source().begin.line == 0) return of(value.source());
  return of(key.source());
}

void Places::note(const std::string& name, const toml::key& key, const toml::node& value) const {
  if (!record_) return;
  const int line = is_override(value.source()) ? 0 : static_cast<int>(key.source().begin.line);
  record_->key_places.insert_or_assign(name, SceneConfig::KeyPlace{of(key, value), line});
}

void Places::warn(const std::string& place, const std::string& what) const {
  if (record_) record_->warnings.push_back(place + ": " + what);
}

void fail(const std::string& place, const std::string& what) {
  throw InputError(place + ": " + what);
}

// A quoted key may hold any character, and a NUL or a control character would cut the message
// short or garble the terminal.
std::string printable(std::string_view key) {
  std::string out;
  for (const char ch : key) {
    const auto u = static_cast<unsigned char>(ch);
    if (u < 0x20 || u == 0x7f) {
      char code[8];
      std::snprintf(code, sizeof code, "\\u%04x", u);
      out += code;
    } else {
      out += ch;
    }
  }
  return out;
}

// ---- Reading one table --------------------------------------------------------------------------

std::string TableReader::name(std::string_view key) const {
  return prefix_.empty() ? printable(key) : prefix_ + "." + printable(key);
}

void TableReader::read(std::string_view key, Real& out, Range range) {
  if (const auto e = find(key)) out = number(*e->node, name(key), place(*e), range);
}

void TableReader::read(std::string_view key, std::optional<Real>& out, Range range) {
  if (const auto e = find(key)) out = number(*e->node, name(key), place(*e), range);
}

void TableReader::read(std::string_view key, bool& out) {
  const auto e = find(key);
  if (!e) return;
  const auto* b = e->node->as_boolean();
  if (!b) fail(place(*e), name(key) + ": expected true or false, got " + type_name(*e->node));
  out = b->get();
}

void TableReader::read(std::string_view key, std::string& out) {
  const auto e = find(key);
  if (!e) return;
  const auto* s = e->node->as_string();
  if (!s) fail(place(*e), name(key) + ": expected a string, got " + type_name(*e->node));
  out = s->get();
}

void TableReader::read(std::string_view key, std::optional<std::vector<Word>>& out) {
  const auto e = find(key);
  if (!e) return;
  const std::string n = name(key);
  const auto* a = e->node->as_array();
  if (!a) fail(place(*e), n + ": expected an array of strings, got " + type_name(*e->node));
  out.emplace();
  for (std::size_t i = 0; i < a->size(); ++i) {
    const toml::node& item = *a->get(i);
    const std::string in = n + "[" + std::to_string(i) + "]";
    const auto* s = item.as_string();
    if (!s) fail(places_.of(item.source()), in + ": expected a string, got " + type_name(item));
    out->push_back({s->get(), places_.of(item.source()), in});
  }
}

void TableReader::read(std::string_view key, Vec3& out, Range range, int checked) {
  const auto e = find(key);
  if (!e) return;
  const auto v = numbers<3>(*e, name(key), range, checked);
  for (int i = 0; i < 3; ++i) out[i] = v[static_cast<std::size_t>(i)];
}

void TableReader::read(std::string_view key, HeightGrid& out, int max_side) {
  const auto e = find(key);
  if (!e) return;
  const std::string n = name(key);
  const auto* rows = e->node->as_array();
  if (!rows)
    fail(place(*e), n + ": expected an array of rows, [[z, z, ...], [z, z, ...], ...], got " +
                        type_name(*e->node));
  const auto limit = static_cast<std::size_t>(max_side);
  if (rows->size() < 2 || rows->size() > limit)
    fail(place(*e), n + " has " + std::to_string(rows->size()) + " rows: expected 2 to " +
                        std::to_string(max_side));
  std::size_t nx = 0;
  for (std::size_t j = 0; j < rows->size(); ++j) {
    const toml::node& row = *rows->get(j);
    const std::string rn = n + "[" + std::to_string(j) + "]";
    const auto* a = row.as_array();
    if (!a)
      fail(places_.of(row.source()), rn + ": expected a row of numbers, got " + type_name(row));
    if (j == 0) {
      nx = a->size();
      if (nx < 2 || nx > limit)
        fail(places_.of(row.source()), rn + " has " + std::to_string(nx) +
                                           " values: expected 2 to " + std::to_string(max_side));
    } else if (a->size() != nx) {
      fail(places_.of(row.source()), rn + " has " + std::to_string(a->size()) + " values but " + n +
                                         "[0] has " + std::to_string(nx) +
                                         ": every row must have the same length");
    }
  }
  out.nx = static_cast<int>(nx);
  out.ny = static_cast<int>(rows->size());
  out.z.assign(nx * rows->size(), 0.0);
  for (std::size_t j = 0; j < rows->size(); ++j) {
    const auto* a = rows->get(j)->as_array();
    for (std::size_t i = 0; i < nx; ++i) {
      const toml::node& c = *a->get(i);
      out.z[j * nx + i] = number(c, n + "[" + std::to_string(j) + "][" + std::to_string(i) + "]",
                                 places_.of(c.source()), kAny);
    }
  }
}

const toml::table* TableReader::table(std::string_view key) {
  const auto e = find(key);
  if (!e) return nullptr;
  if (const auto* t = e->node->as_table()) return t;
  fail(place(*e), name(key) + ": expected a table [" + name(key) + "], got " + type_name(*e->node));
}

const toml::array* TableReader::array_of_tables(std::string_view key) {
  const auto e = find(key);
  if (!e) return nullptr;
  const std::string n = name(key);
  const auto* a = e->node->as_array();
  if (!a)
    fail(place(*e), n + ": expected an array of tables [[" + n + "]], got " + type_name(*e->node));
  for (std::size_t i = 0; i < a->size(); ++i) {
    const toml::node& item = *a->get(i);
    if (!item.is_table())
      fail(places_.of(item.source()),
           n + "[" + std::to_string(i) + "]: expected a table, got " + type_name(item));
  }
  return a;
}

std::string TableReader::place_at(std::string_view key) const {
  const auto it = table_.find(key);
  return it != table_.end() ? places_.of(it->first, it->second) : places_.of(table_.source());
}

void TableReader::fail_at(std::string_view key, const std::string& what) const {
  fail(place_at(key), what);
}

void TableReader::read_name(std::string_view key, std::string& out) {
  read(key, out);
  if (std::any_of(out.begin(), out.end(), [](char ch) {
        const auto u = static_cast<unsigned char>(ch);
        return u < 0x20 || u == 0x7f;
      }))
    fail_at(key, name(key) + " = \"" + printable(out) +
                     "\" holds a control character: a name is one line of printable text");
}

void TableReader::warn_at(std::string_view key, const std::string& what) const {
  places_.warn(place_at(key), what);
}

bool TableReader::in_file(std::string_view key) const {
  const auto it = table_.find(key);
  return it != table_.end() && !places_.is_override(it->second.source());
}

void TableReader::require(std::string_view key, std::string_view expected) const {
  if (!table_.contains(key))
    fail_at(key, name(key) + " is missing: expected " + std::string(expected));
}

void TableReader::finish(std::string_view what) const {
  const toml::key* worst = nullptr;
  const toml::node* worst_value = nullptr;
  const auto rank = [](const toml::key& k) {  // overrides carry no line: report them last
    const auto& b = k.source().begin;
    return std::pair(b.line == 0 ? std::numeric_limits<toml::source_index>::max() : b.line,
                     b.column);
  };
  for (auto&& [k, v] : table_) {
    if (std::find(known_.begin(), known_.end(), k.str()) != known_.end()) continue;
    if (!worst || rank(k) < rank(*worst)) {
      worst = &k;
      worst_value = &v;
    }
  }
  if (worst)
    fail(places_.of(*worst, *worst_value), name(worst->str()) + " is not a key of " +
                                               std::string(what) + " (keys: " + join(known_, ", ") +
                                               ")");
}

std::optional<TableReader::Entry> TableReader::find(std::string_view key) {
  if (std::find(known_.begin(), known_.end(), key) == known_.end()) known_.emplace_back(key);
  const auto it = table_.find(key);
  if (it == table_.end()) return std::nullopt;
  places_.note(name(key), it->first, it->second);
  return Entry{&it->first, &it->second};
}

std::int64_t TableReader::integer(const Entry& e, const std::string& n, Range range) const {
  std::int64_t v = 0;
  if (const auto* i = e.node->as_integer()) {
    v = i->get();
  } else if (const auto* f = e.node->as_floating_point()) {
    const Real x = f->get();
    if (!std::isfinite(x)) fail(place(e), n + " = " + format_real(x) + " is not a finite number");
    if (std::trunc(x) != x || std::abs(x) >= 9.2e18)
      fail(place(e), n + ": expected an integer, got " + format_real(x));
    v = static_cast<std::int64_t>(x);
  } else {
    fail(place(e), n + ": expected an integer, got " + type_name(*e.node));
  }
  if (!range.contains(static_cast<Real>(v)))
    fail(place(e), n + " = " + std::to_string(v) + " " + range.violation(true));
  return v;
}

const toml::array& TableReader::array_of(const Entry& e, const std::string& n,
                                         std::size_t size) const {
  const std::string expected = "expected an array of " + std::to_string(size) + " numbers, got ";
  const auto* a = e.node->as_array();
  if (!a) fail(place(e), n + ": " + expected + type_name(*e.node));
  if (a->size() != size)
    fail(place(e), n + ": " + expected + std::to_string(a->size()) +
                       (a->size() == 1 ? " element" : " elements"));
  return *a;
}

Real TableReader::number(const toml::node& n, const std::string& name, const std::string& place,
                         Range range) {
  Real v = 0;
  if (const auto* i = n.as_integer()) {
    v = static_cast<Real>(i->get());
  } else if (const auto* f = n.as_floating_point()) {
    v = f->get();
  } else {
    fail(place, name + ": expected a number, got " + type_name(n));
  }
  if (!std::isfinite(v)) fail(place, name + " = " + format_real(v) + " is not a finite number");
  if (!range.contains(v)) fail(place, name + " = " + value_text(n) + " " + range.violation(false));
  return v;
}

}  // namespace sandflow::loader

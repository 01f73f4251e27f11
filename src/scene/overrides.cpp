// --set KEY=VALUE (overrides.hpp): the argument split into key and value, the key's dotted path
// walked in the parsed document, and the value parsed (through the guard of toml_guard.hpp) and
// put at its end.

#include "scene/overrides.hpp"

#include <algorithm>
#include <charconv>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "scene/table_reader.hpp"
#include "scene/toml_guard.hpp"

namespace sandflow {

namespace loader {
namespace {

// "emitter[0].rate" or "emitter.0.rate" -> {"emitter", "0", "rate"}.
std::vector<std::string> split_key(const std::string& key, const std::string& where) {
  const auto malformed = [&] {
    fail(where, "malformed key " + in_quotes(key) +
                    ": expected a dotted path such as material.friction or emitter[0].rate");
  };
  std::string dotted;
  for (std::size_t i = 0; i < key.size(); ++i) {
    if (key[i] == '[') {
      const std::size_t close = key.find(']', i);
      if (close == std::string::npos || close == i + 1) malformed();
      const std::string index = key.substr(i + 1, close - i - 1);
      if (!std::all_of(index.begin(), index.end(), [](char ch) { return ch >= '0' && ch <= '9'; }))
        malformed();
      dotted += "." + index;
      i = close;
      if (i + 1 < key.size() && key[i + 1] != '.' && key[i + 1] != '[') malformed();
    } else if (key[i] == ']') {
      malformed();
    } else {
      dotted += key[i];
    }
  }
  std::vector<std::string> segments;
  std::size_t begin = 0;
  while (true) {
    const std::size_t dot = dotted.find('.', begin);
    segments.push_back(dotted.substr(begin, dot == std::string::npos ? dot : dot - begin));
    if (segments.back().empty()) malformed();
    if (dot == std::string::npos) break;
    begin = dot + 1;
  }
  return segments;
}

std::optional<std::size_t> parse_index(const std::string& s) {
  std::size_t i = 0;
  const auto res = std::from_chars(s.data(), s.data() + s.size(), i);
  if (res.ec != std::errc() || res.ptr != s.data() + s.size()) return std::nullopt;
  return i;
}

// The override's value as a one-key document {v = VALUE}, parsed with "--set KEY" as its source
// path. Text that is not a TOML value is taken as a bare string, so --set simulation.mode=dem
// works.
toml::table parse_override_value(const Override& o, const std::string& where) {
  const std::string doc = "v = " + o.value;
  try {
    if (!toml_hazard(doc)) {  // else a string (toml++ could not parse it safely)
      toml::table t = toml::parse(doc, std::string_view(where));
      if (t.size() == 1 && t.contains("v")) return t;  // not "1\nw = 2" smuggling in more keys
    }
  } catch (const toml::parse_error&) {
  }
  // a number no double holds (1e400) fails to parse like a word, but is not meant as a string
  double number = 0;
  const char* end = o.value.data() + o.value.size();
  if (const auto [p, ec] = std::from_chars(o.value.data(), end, number);
      p == end && ec == std::errc::result_out_of_range)
    fail(where,
         "the value " + o.value + " is beyond the range of a double (about 1e-308 to 1e308)");
  std::ostringstream quoted;
  quoted << toml::value<std::string>(o.value);
  const std::string as_string = "v = " + quoted.str();
  if (const auto h = toml_hazard(as_string))
    fail(where, "cannot read the value " + in_quotes(o.value) + ": " + h->what);
  try {
    return toml::parse(as_string, std::string_view(where));
  } catch (const toml::parse_error& err) {
    fail(where,
         "cannot read the value " + in_quotes(o.value) + ": " + std::string(err.description()));
  }
}

}  // namespace

// Grafts one override onto the parsed document. Tables on the way must exist (an index past the
// last [[emitter]] is an error), except the plain top-level tables, which a file may leave out.
void apply_override(toml::table& root, const Override& o) {
  const std::string where = "--set " + o.key;
  const std::vector<std::string> segments = split_key(o.key, where);

  toml::node* at = &root;
  std::string walked;  // the path so far, named as in messages: emitter[0]
  for (std::size_t s = 0; s + 1 < segments.size(); ++s) {
    const std::string& seg = segments[s];
    if (auto* t = at->as_table()) {
      toml::node* child = t->get(seg);
      if (!child) {
        const bool plain = seg == "scene" || seg == "material" || seg == "simulation" ||
                           seg == "stiffness" || seg == "surface" || seg == "output" ||
                           seg == "camera";
        if (t != &root || !plain)
          fail(where, "the scene has no table " + (walked.empty() ? seg : walked + "." + seg));
        child = &t->insert_or_assign(seg, toml::table{}).first->second;
      }
      walked = walked.empty() ? seg : walked + "." + seg;
      at = child;
    } else if (auto* a = at->as_array()) {
      const auto i = parse_index(seg);
      if (!i) fail(where, walked + " is an array: index it with a number, as in " + walked + ".0");
      if (*i >= a->size())
        fail(where, "the scene has no " + walked + "[" + seg + "] (it has " +
                        std::to_string(a->size()) + ")");
      walked += "[" + seg + "]";
      at = a->get(*i);
    } else {
      fail(where, walked + " is " + type_name(*at) + ", not a table");
    }
  }

  auto* target = at->as_table();
  if (!target) {
    if (at->is_array())
      fail(where, "cannot set one element of " + walked + "; set the whole array instead");
    fail(where, walked + " is " + type_name(*at) + ", not a table");
  }
  toml::table parsed = parse_override_value(o, where);
  // Moving (not copying) the node keeps its source region, hence its "--set KEY" place.
  parsed.get("v")->visit(
      [&](auto& node) { target->insert_or_assign(segments.back(), std::move(node)); });
}

}  // namespace loader

Override parse_override(const std::string& arg) {
  const auto trim = [](std::string s) {
    const auto first = s.find_first_not_of(" \t");
    const auto last = s.find_last_not_of(" \t");
    return first == std::string::npos ? std::string() : s.substr(first, last - first + 1);
  };
  const std::size_t eq = arg.find('=');
  if (eq == std::string::npos)
    throw InputError("--set " + arg + ": expected KEY=VALUE, as in --set material.friction=0.5");
  Override o{trim(arg.substr(0, eq)), trim(arg.substr(eq + 1))};
  if (o.key.empty())
    throw InputError("--set " + arg +
                     ": the key is empty; expected KEY=VALUE, as in --set material.friction=0.5");
  return o;
}

}  // namespace sandflow

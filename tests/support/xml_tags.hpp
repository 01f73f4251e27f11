// The attributes of the XML tags a test reads back (VTK .vtp and .pvd files). A scan, not a
// parser: enough for files the program wrote. (No std::regex: GCC 12 reports false
// maybe-uninitialized warnings inside <regex> under the sanitizer build, which uses -Werror.)
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace sandflow::test {

/// Every `<tag ...>` in `text`, in order, each as its attributes name -> value.
inline std::vector<std::map<std::string, std::string>> xml_tags(std::string_view text,
                                                                 std::string_view tag) {
  std::vector<std::map<std::string, std::string>> out;
  const std::string open = "<" + std::string(tag) + " ";
  for (std::size_t at = text.find(open); at != std::string_view::npos;
       at = text.find(open, at + 1)) {
    const std::size_t end = text.find('>', at);
    if (end == std::string_view::npos) break;
    std::map<std::string, std::string> attrs;
    std::size_t p = at + open.size();
    while (true) {
      const std::size_t eq = text.find("=\"", p);
      if (eq == std::string_view::npos || eq > end) break;
      std::size_t name = text.find_last_of(" \t\n", eq);
      name = name == std::string_view::npos || name < p - 1 ? p : name + 1;
      const std::size_t close = text.find('"', eq + 2);
      if (close == std::string_view::npos || close > end) break;
      attrs[std::string(text.substr(name, eq - name))] =
          std::string(text.substr(eq + 2, close - eq - 2));
      p = close + 1;
    }
    out.push_back(std::move(attrs));
  }
  return out;
}

}  // namespace sandflow::test

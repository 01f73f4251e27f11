// A small well-formedness check of the report's HTML, and counts of what it holds. Not an HTML
// parser: it holds the page to the stricter rules the writer keeps (every element closed or
// written as <x/>, every & an entity), which is what makes it safe to read anywhere.
#pragma once

#include <cctype>
#include <string>
#include <vector>

namespace sandflow_test {

/// "" when every opened tag is closed in order, void elements are written <x .../> and every &
/// starts an entity; else what is wrong and where (byte offset).
inline std::string html_problem(const std::string& html) {
  std::vector<std::string> open;
  std::size_t k = 0;
  while (k < html.size()) {
    const char c = html[k];
    if (c == '&') {
      std::size_t e = k + 1;
      while (e < html.size() && (std::isalnum(static_cast<unsigned char>(html[e])) || html[e] == '#'))
        ++e;
      if (e == k + 1 || e >= html.size() || html[e] != ';')
        return "a bare & at " + std::to_string(k);
      k = e + 1;
      continue;
    }
    if (c == '>') return "a bare > at " + std::to_string(k);
    if (c != '<') {
      ++k;
      continue;
    }
    if (html.compare(k, 4, "<!--") == 0) {
      const std::size_t e = html.find("-->", k);
      if (e == std::string::npos) return "an unclosed comment at " + std::to_string(k);
      k = e + 3;
      continue;
    }
    // the tag, to its '>' outside quotes
    std::size_t e = k + 1;
    char quote = 0;
    for (; e < html.size(); ++e) {
      if (quote) {
        if (html[e] == quote) quote = 0;
        else if (html[e] == '<') return "a < inside an attribute at " + std::to_string(e);
      } else if (html[e] == '"' || html[e] == '\'') {
        quote = html[e];
      } else if (html[e] == '>') {
        break;
      } else if (html[e] == '<') {
        return "a < inside a tag at " + std::to_string(e);
      }
    }
    if (e >= html.size()) return "an unclosed tag at " + std::to_string(k);
    const std::string tag = html.substr(k + 1, e - k - 1);
    k = e + 1;
    if (tag.empty()) return "an empty tag at " + std::to_string(k);
    if (tag[0] == '!') continue;  // <!DOCTYPE html>
    const bool closing = tag[0] == '/';
    std::size_t n0 = closing ? 1 : 0, n1 = n0;
    while (n1 < tag.size() && (std::isalnum(static_cast<unsigned char>(tag[n1])) || tag[n1] == '-'))
      ++n1;
    const std::string name = tag.substr(n0, n1 - n0);
    if (name.empty()) return "a tag without a name at " + std::to_string(k);
    if (closing) {
      if (open.empty() || open.back() != name)
        return "</" + name + "> closes " + (open.empty() ? "nothing" : "<" + open.back() + ">") +
               " at " + std::to_string(k);
      open.pop_back();
    } else if (tag.back() != '/') {
      for (const char* v : {"meta", "img", "br", "hr", "link", "input"})
        if (name == v) return "<" + name + "> not written as <" + name + "/> at " + std::to_string(k);
      open.push_back(name);
      // the text of <style> is CSS, not markup
      if (name == "style") {
        const std::size_t end = html.find("</style>", k);
        if (end == std::string::npos) return "an unclosed <style>";
        k = end;
      }
    }
  }
  if (!open.empty()) return "<" + open.back() + "> is never closed";
  return "";
}

/// How many times `what` occurs in `text`.
inline std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

/// The points="..." of every <polyline>, each as its number of x,y pairs, keyed by data-series.
struct Polyline {
  std::string series;
  std::size_t points = 0;
};
inline std::vector<Polyline> polylines(const std::string& html) {
  std::vector<Polyline> out;
  for (std::size_t p = html.find("<polyline"); p != std::string::npos;
       p = html.find("<polyline", p + 1)) {
    const std::size_t end = html.find('>', p);
    const std::string tag = html.substr(p, end - p);
    Polyline pl;
    if (const std::size_t s = tag.find("data-series=\""); s != std::string::npos)
      pl.series = tag.substr(s + 13, tag.find('"', s + 13) - s - 13);
    if (const std::size_t s = tag.find("points=\""); s != std::string::npos) {
      const std::string pts = tag.substr(s + 8, tag.find('"', s + 8) - s - 8);
      pl.points = occurrences(pts, ",");
    }
    out.push_back(pl);
  }
  return out;
}

/// The part of the page inside <section id="ID"> ... </section> ("" when there is none).
inline std::string section_of(const std::string& html, const std::string& id) {
  const std::size_t start = html.find("<section id=\"" + id + "\">");
  if (start == std::string::npos) return "";
  return html.substr(start, html.find("</section>", start) - start);
}

}  // namespace sandflow_test

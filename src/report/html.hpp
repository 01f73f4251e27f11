// Small pieces of HTML writing shared by the report's parts: escaping and data: URIs.
#pragma once

#include <string>
#include <string_view>

namespace sandflow {

/// `text` with &, <, >, " and ' replaced by entities: safe in element content and in quoted
/// attribute values.
std::string html_escape(std::string_view text);

/// RFC 4648 base64 (with padding, no line breaks), for images embedded as data: URIs.
std::string base64_encode(std::string_view bytes);

}  // namespace sandflow

#pragma once
// Text encodings for the self-contained HTML report: HTML escaping, Base64 (embedded PNGs and binary arrays)
// and JSON that can sit inside a <script> element.

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace semslam {

// Escapes & < > " ' for HTML text and attribute values.
std::string HtmlEscape(std::string_view text);

// Standard Base64 (RFC 4648, '+' and '/', '=' padding, no line breaks).
std::string Base64Encode(std::span<const std::uint8_t> bytes);
std::string Base64Encode(std::string_view bytes);

// JSON text made safe to embed in <script type="application/json">: every '<' becomes "\u003c" (JSON only
// has '<' inside strings, where the escape means the same), so "</script>" or "<!--" in a landmark name
// cannot end or confuse the element. JSON.parse of the result gives back the same value.
std::string JsonForScriptElement(std::string_view json);

}  // namespace semslam

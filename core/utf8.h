#pragma once
// UTF-8 validation. Everything a command writes to JSON (results.json, manifests, model file
// metadata) must be UTF-8, and a path or config value that is not fails only when the JSON is
// written, after the work is done: so such input is rejected before any work starts.

#include <optional>
#include <string>

namespace cgsr {

// The offset of the first byte that does not belong to a well-formed UTF-8 sequence (overlong
// forms, surrogates and code points beyond U+10FFFF included), or nothing when `text` is valid.
std::optional<size_t> first_invalid_utf8(const std::string& text);

// Throws a user error at `context` naming `what` ("the --out path") and the offending byte.
void require_utf8(const std::string& text, const std::string& context, const std::string& what);

}  // namespace cgsr

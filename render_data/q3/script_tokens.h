#pragma once
// Tokens of Quake III text scripts (entity strings, .shader files): whitespace separates, "//" and
// "/* */" are comments, "..." quotes a token (no escapes), and braces are tokens of their own.
// Each token remembers its line, so parsers can treat a line as one directive and report where.

#include <string>
#include <vector>

namespace cgsr::q3 {

struct ScriptToken {
  enum Kind { Open, Close, Text } kind = Text;
  std::string text;  // the token without quotes; "{" or "}" for braces
  int line = 1;
};

// ASCII lower case: script keywords and game paths compare case-insensitively.
std::string ascii_lower(std::string text);

// cgsr::Error(context, "line N: unterminated ...") for an open quote or block comment.
std::vector<ScriptToken> tokenize_script(const std::string& text, const std::string& context);

}  // namespace cgsr::q3

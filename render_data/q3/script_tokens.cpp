#include "render_data/q3/script_tokens.h"

#include <cctype>

#include "core/error.h"

namespace cgsr::q3 {

std::string ascii_lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

std::vector<ScriptToken> tokenize_script(const std::string& text, const std::string& context) {
  std::vector<ScriptToken> out;
  const size_t n = text.size();
  size_t pos = 0;
  int line = 1;
  auto fail = [&](int at, const std::string& what) { throw Error(context, "line " + std::to_string(at) + ": " + what); };
  while (pos < n) {
    const char c = text[pos];
    if (c == '\n') {
      ++line;
      ++pos;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++pos;
    } else if (c == '/' && pos + 1 < n && text[pos + 1] == '/') {
      while (pos < n && text[pos] != '\n') ++pos;
    } else if (c == '/' && pos + 1 < n && text[pos + 1] == '*') {
      const int start = line;
      const size_t close = text.find("*/", pos + 2);
      if (close == std::string::npos) fail(start, "unterminated /* comment");
      for (size_t i = pos; i < close; ++i) line += text[i] == '\n';
      pos = close + 2;
    } else if (c == '{' || c == '}') {
      out.push_back({c == '{' ? ScriptToken::Open : ScriptToken::Close, std::string(1, c), line});
      ++pos;
    } else if (c == '"') {
      const size_t close = text.find('"', pos + 1);
      if (close == std::string::npos) fail(line, "unterminated quoted string");
      out.push_back({ScriptToken::Text, text.substr(pos + 1, close - pos - 1), line});
      for (size_t i = pos; i < close; ++i) line += text[i] == '\n';
      pos = close + 1;
    } else {
      const size_t start = pos;
      while (pos < n && !std::isspace(static_cast<unsigned char>(text[pos])) && text[pos] != '{' && text[pos] != '}' &&
             text[pos] != '"' && !(text[pos] == '/' && pos + 1 < n && (text[pos + 1] == '/' || text[pos + 1] == '*')))
        ++pos;
      out.push_back({ScriptToken::Text, text.substr(start, pos - start), line});
    }
  }
  return out;
}

}  // namespace cgsr::q3

#include "core/text.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numeric>
#include <sstream>

#include "core/config.h"
#include "core/error.h"

namespace cgsr {

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  std::iota(row.begin(), row.end(), size_t{0});
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      const size_t substitute = diagonal + (std::tolower(a[i - 1]) == std::tolower(b[j - 1]) ? 0 : 1);
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, substitute});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::string closest_match(const std::string& name, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_distance = std::string::npos;
  for (const auto& candidate : candidates) {
    const size_t d = edit_distance(name, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  // A typo changes a few characters; beyond a third of the word it is a different word.
  const size_t limit = std::max<size_t>(2, name.size() / 3);
  return best_distance <= limit ? best : std::string();
}

std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates) {
  const std::string match = closest_match(name, candidates);
  return match.empty() ? std::string() : " (did you mean '" + match + "'?)";
}

std::string join(const std::vector<std::string>& parts, const std::string& separator) {
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) {
    if (i) out += separator;
    out += parts[i];
  }
  return out;
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (true) {
    const size_t end = text.find(separator, start);
    parts.push_back(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return parts;
}

std::pair<int, int> parse_size(const std::string& text, const std::string& what) {
  const auto parts = split(text, 'x');
  constexpr size_t kMaxDigits = 6;
  auto is_number = [](const std::string& s) {
    return !s.empty() && s.size() <= kMaxDigits && std::all_of(s.begin(), s.end(), ::isdigit);
  };
  if (parts.size() != 2 || !is_number(parts[0]) || !is_number(parts[1]))
    throw Error(what, "expected a size WxH such as 320x240, got '" + text + "'");
  const int w = std::stoi(parts[0]);
  const int h = std::stoi(parts[1]);
  constexpr double kLargest = 999999;  // kMaxDigits digits
  if (w <= 0) throw Error(what, "size " + text + ": width " + config::out_of_range(parts[0], 1, kLargest));
  if (h <= 0) throw Error(what, "size " + text + ": height " + config::out_of_range(parts[1], 1, kLargest));
  return {w, h};
}

std::optional<std::pair<int, int>> parse_frame_range(const std::string& text) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) return std::nullopt;
  try {
    size_t used_a = 0, used_b = 0;
    const std::string a = text.substr(0, colon), b = text.substr(colon + 1);
    const int first = std::stoi(a, &used_a), end = std::stoi(b, &used_b);
    if (used_a != a.size() || used_b != b.size() || first < 0 || end <= first) return std::nullopt;
    return std::pair{first, end};
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::string fixed(double v, int digits) {
  if (!std::isfinite(v)) return "NA";
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(digits);
  s << v;
  return s.str();
}

}  // namespace cgsr

#pragma once
// Small string helpers shared by config validation, registries and the CLI.

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace cgsr {

// Edit distance between two strings (insertions, deletions, substitutions).
size_t edit_distance(const std::string& a, const std::string& b);

// The candidate closest to `name`, or "" when none is close enough to be a plausible typo.
std::string closest_match(const std::string& name, const std::vector<std::string>& candidates);

// " (did you mean 'x'?)" or "" when nothing is close.
std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates);

// "a, b, c"
std::string join(const std::vector<std::string>& parts, const std::string& separator = ", ");

// Splits "a.b.c" on the separator; empty parts are kept so callers can reject them.
std::vector<std::string> split(const std::string& text, char separator);

// Parses "WxH" (e.g. "320x240") into width and height; throws cgsr::Error naming `what`.
std::pair<int, int> parse_size(const std::string& text, const std::string& what);

// Parses a frame range "A:B" (A included, B not, whole numbers 0 <= A < B); nothing when malformed.
std::optional<std::pair<int, int>> parse_frame_range(const std::string& text);

// `v` with `digits` decimals ("25.412"); "NA" when not finite.
std::string fixed(double v, int digits);

}  // namespace cgsr

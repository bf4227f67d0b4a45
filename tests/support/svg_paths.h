#pragma once
// The paths of an SVG file as Cairo writes them (<path style="..." d="..."/>): each one's stroke
// colour, whether it is dashed, and the numbers of its outline, so that a test can find the
// lines a plot drew and where they run.

#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include "core/canvas.h"

namespace cgsr::test {

struct SvgPath {
  bool stroked = false, dashed = false;
  bool straight = false;             // straight segments only (M, L, Z): a line or box, not a round marker
  Rgb stroke{-1, -1, -1};            // the stroke colour, 0..255 (-1 when not stroked)
  std::vector<double> xs, ys;        // the coordinates of a polyline ("M x y L x y ...")
  std::vector<std::string> numbers;  // every number in `d` as written
};

inline std::vector<SvgPath> svg_paths(const std::string& svg) {
  std::vector<SvgPath> out;
  static const std::regex path(R"re(<path style="([^"]*)" d="([^"]*)"/>)re");
  static const std::regex stroke(R"re(stroke:rgb\(([0-9.]+)%,([0-9.]+)%,([0-9.]+)%\))re");
  static const std::regex number(R"([-+0-9.eEaAnNiIfF]+)");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), path); it != std::sregex_iterator(); ++it) {
    SvgPath p;
    const std::string style = (*it)[1], d = (*it)[2];
    std::smatch m;
    if (std::regex_search(style, m, stroke) && style.find("stroke:none") == std::string::npos) {
      p.stroked = true;
      for (int c = 0; c < 3; ++c) p.stroke[c] = static_cast<int>(std::lround(std::stod(m[c + 1]) * 2.55));
    }
    p.dashed = style.find("stroke-dasharray") != std::string::npos;
    p.straight = d.find_first_not_of("MLZ0123456789.-+eE ") == std::string::npos;
    std::vector<double> values;
    for (auto n = std::sregex_iterator(d.begin(), d.end(), number); n != std::sregex_iterator(); ++n) {
      p.numbers.push_back(n->str());
      try {
        values.push_back(std::stod(n->str()));
      } catch (const std::exception&) {
        values.push_back(NAN);
      }
    }
    for (size_t i = 0; i + 1 < values.size(); i += 2) {
      p.xs.push_back(values[i]);
      p.ys.push_back(values[i + 1]);
    }
    out.push_back(p);
  }
  return out;
}

}  // namespace cgsr::test

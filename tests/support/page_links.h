#pragma once
// The files an HTML page links to (src and href values that are not anchors), and those of them
// that do not exist next to the page.

#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "tests/support/cli_runner.h"

namespace cgsr::test {

inline std::vector<std::string> page_links(const std::filesystem::path& page) {
  const std::string html = slurp(page);
  const std::regex link(R"re((?:src|href)="([^"#][^"]*)")re");
  std::vector<std::string> out;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), link); it != std::sregex_iterator(); ++it)
    out.push_back((*it)[1]);
  return out;
}

inline std::vector<std::string> missing_links(const std::filesystem::path& page) {
  std::vector<std::string> missing;
  for (const auto& l : page_links(page))
    if (!std::filesystem::exists(page.parent_path() / l)) missing.push_back(l);
  return missing;
}

}  // namespace cgsr::test

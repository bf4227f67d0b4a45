#pragma once
// The report as one HTML page, index.html in the report directory: opened from the disk in any
// browser with no server, and needing nothing outside the directory (styles and the script that
// sorts the tables are inline; plots are SVG files, image comparisons PNG files next to it).
// It holds the verdict with each check's figures (when there is one), every table (sortable by
// any column), each table's PSNR-latency plot and PSNR per frame (frame_plot.h), the image
// comparisons, and the pattern chosen per frame. A picture that fails to load is reported on the
// browser's console.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace cgsr {

// `report` is what write_report() returned (tables, evaluations, comparisons, pattern choices);
// `verdict` is a Verdict's to_json(), or null for none.
void write_report_page(const std::filesystem::path& dir, const nlohmann::ordered_json& report,
                       const nlohmann::ordered_json& verdict = nullptr);

// `text` with &, <, >, " and ' escaped for HTML text and attribute values.
std::string html_escape(const std::string& text);

}  // namespace cgsr

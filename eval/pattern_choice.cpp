#include "eval/pattern_choice.h"

#include <sstream>

#include "core/error.h"
#include "core/plot.h"
#include "core/text.h"

namespace cgsr {

std::optional<PatternChoices> pattern_choices(const EvalResult& result) {
  PatternChoices out;
  for (const auto& f : result.frames) {
    if (!f.choice) continue;
    FrameChoice c;
    c.frame = f.frame;
    c.pattern = f.choice->pattern;
    c.channel_fraction = f.choice->channel_fraction;
    c.edge_fraction = f.edge_fraction;
    c.psnr = f.psnr;
    out.frames.push_back(c);
    ++out.usage[c.pattern];
  }
  if (out.frames.empty()) return std::nullopt;
  return out;
}

std::string usage_text(const PatternChoices& choices) {
  std::string text;
  const double total = static_cast<double>(choices.frames.size());
  for (const auto& [pattern, n] : choices.usage)
    text += (text.empty() ? "" : ", ") + ("pattern " + std::to_string(pattern) + ": " + std::to_string(n) +
                                          " frames (" + fixed(100.0 * n / total, 0) + "%)");
  return text;
}

std::string pattern_choice_markdown(const std::string& model, const PatternChoices& choices, const std::string& plot) {
  std::ostringstream md;
  md << "#### " << model << ": the pattern chosen per frame\n\n";
  md << "Usage: " << usage_text(choices) << ". Pattern 0 is the widest (the static network).\n\n";
  md << "| Frame | Edge pixels (%) | Pattern | Channels kept (%) | PSNR (dB) |\n|---:|---:|---:|---:|---:|\n";
  for (const auto& c : choices.frames)
    md << "| " << c.frame << " | " << (c.edge_fraction ? fixed(100.0 * *c.edge_fraction, 2) : "-") << " | "
       << c.pattern << " | " << fixed(100.0 * c.channel_fraction, 0) << " | " << fixed(c.psnr, 2) << " |\n";
  if (!plot.empty()) md << "\n![" << model << ": pattern per frame against edge density](" << plot << ")\n";
  return md.str() + "\n";
}

ScatterPlot pattern_choice_plot(const std::string& model, const PatternChoices& choices) {
  ScatterPlot plot;
  plot.title = model + ": pattern chosen per frame";
  plot.x_label = "geometry-edge pixels of the frame (%)";
  plot.y_label = "channels the chosen pattern keeps (%)";
  // One series per pattern, so the legend reads as the usage shares.
  const std::vector<Rgb> colours = {{220, 40, 40}, {40, 90, 180}, {40, 150, 60}, {200, 130, 20}, {130, 60, 170}};
  std::map<int, PlotSeries> series;
  for (const auto& c : choices.frames) {
    if (!c.edge_fraction) continue;
    auto [it, fresh] = series.try_emplace(c.pattern);
    if (fresh) {
      it->second.name = "pattern " + std::to_string(c.pattern) + " (" + std::to_string(choices.usage.at(c.pattern)) +
                        " frames)";
      it->second.colour = colours[static_cast<size_t>(c.pattern) % colours.size()];
    }
    it->second.points.push_back({100.0 * *c.edge_fraction, 100.0 * c.channel_fraction, std::to_string(c.frame)});
  }
  if (series.empty())
    throw Error(model, "no frame of " + model + " has an edge density (the data set has no edge channel)");
  for (auto& [pattern, s] : series) plot.series.push_back(std::move(s));
  plot.notes.push_back("labels: frame numbers");
  return plot;
}

}  // namespace cgsr

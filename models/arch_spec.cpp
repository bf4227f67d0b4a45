#include "models/arch_spec.h"

#include <algorithm>
#include <set>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/text.h"
#include "models/backbone_registry.h"

namespace cgsr {

// ---- GroupWidths -------------------------------------------------------------------------------

int GroupWidths::at(const std::string& group) const {
  for (const auto& [name, width] : entries_)
    if (name == group) return width;
  std::vector<std::string> names;
  for (const auto& e : entries_) names.push_back(e.first);
  throw Error("arch spec", "no layer group '" + group + "'" + did_you_mean(group, names), ErrorKind::Internal);
}

bool GroupWidths::contains(const std::string& group) const {
  for (const auto& e : entries_)
    if (e.first == group) return true;
  return false;
}

void GroupWidths::set(const std::string& group, int width) {
  for (auto& e : entries_)
    if (e.first == group) {
      e.second = width;
      return;
    }
  entries_.emplace_back(group, width);
}

namespace config {
GroupWidths Codec<GroupWidths>::decode(const YAML::Node& node, const Cursor& at) {
  if (!node.IsMap()) at.fail(node, "expected a map of layer group: width, got " + detail::describe(node));
  GroupWidths widths;
  for (const auto& kv : node) {
    const auto key = kv.first.as<std::string>();
    if (widths.contains(key)) at.child(key).fail(kv.first, "layer group '" + key + "' is listed twice");
    widths.set(key, Codec<int>::decode(kv.second, at.child(key)));
  }
  return widths;
}

YAML::Node Codec<GroupWidths>::encode(const GroupWidths& widths) {
  YAML::Node n(YAML::NodeType::Map);
  for (const auto& [name, width] : widths.entries()) n[name] = width;
  return n;
}
}  // namespace config

// ---- spec --------------------------------------------------------------------------------------

const std::vector<std::string>& EnumNames<RitSource>::names() {
  static const std::vector<std::string> names = {"lr", "hr_pooled", "hr_unshuffle", "hr_fuse", "hr_unshuffle+hr_fuse"};
  return names;
}
const std::vector<std::string>& EnumNames<RitFusion>::names() {
  static const std::vector<std::string> names = {"concat", "add"};
  return names;
}
const std::vector<std::string>& EnumNames<WarpFilter>::names() {
  static const std::vector<std::string> names = {"bilinear", "bicubic"};
  return names;
}
const std::vector<std::string>& EnumNames<ImageSkip>::names() {
  static const std::vector<std::string> names = {"bilinear", "bicubic"};
  return names;
}
const std::vector<std::string>& EnumNames<Colors>::names() {
  static const std::vector<std::string> names = {"rgb", "y"};
  return names;
}

int ArchSpec::group_width(const std::string& group) const {
  if (group == "rit") return rit.width;
  if (group == "rit_hr") return rit.hr_width;
  if (group == "geometry") return geometry.width;
  return widths.at(group);
}

void ArchSpec::set_group_width(const std::string& group, int width) {
  if (group == "rit")
    rit.width = width;
  else if (group == "rit_hr")
    rit.hr_width = width;
  else if (group == "geometry")
    geometry.width = width;
  else
    widths.set(group, width);
}

std::vector<RenderChannel> ArchSpec::input_channels() const {
  return rit.enabled ? rit.render_channels() : std::vector<RenderChannel>{};
}

namespace {

struct Problem {
  std::string key;  // dotted path of the offending key, e.g. "widths.block3_a"
  std::string message;
  bool at_key = false;  // the key itself is wrong (point at it, not at its value)
};

int effective_blocks(const ArchSpec& spec, const BackboneInfo& info) {
  return spec.blocks < 0 ? info.default_blocks : spec.blocks;
}

// Everything wrong with a spec, resolved or not (missing blocks/widths mean defaults). Stops at
// the first problem that makes later checks meaningless (unknown backbone, bad scale).
std::vector<Problem> find_problems(const ArchSpec& spec) {
  std::vector<Problem> problems;
  const auto& registry = backbone_registry();
  if (!registry.contains(spec.backbone)) {
    problems.push_back({"backbone", "unknown backbone '" + spec.backbone + "'" +
                                        did_you_mean(spec.backbone, registry.names()) +
                                        "; valid: " + join(registry.names())});
    return problems;
  }
  const BackboneInfo& info = registry.get(spec.backbone);
  if (spec.scale < 2 || spec.scale > 4) {
    problems.push_back({"scale", config::out_of_range(spec.scale, 2, 4)});
    return problems;
  }
  if (spec.colors == Colors::Y && !info.supports_y)
    problems.push_back({"colors", spec.backbone + " works on RGB only (colors: y is for srcnn)"});
  if (spec.image_skip != ImageSkip::Bilinear && !info.has_image_skip)
    problems.push_back({"image_skip", spec.backbone + " adds no interpolated image to its output (image_skip is for pan)"});
  if (spec.blocks >= 0 && (spec.blocks < info.min_blocks || spec.blocks > info.max_blocks))
    problems.push_back({"blocks", info.max_blocks == 0
                                      ? spec.backbone + " has no residual blocks; blocks must be 0"
                                      : config::out_of_range(spec.blocks, info.min_blocks, info.max_blocks)});
  const int blocks = std::clamp(effective_blocks(spec, info), info.min_blocks, info.max_blocks);
  std::vector<std::string> names;
  for (const auto& g : info.groups(spec.scale, blocks)) names.push_back(g.name);
  for (const auto& [group, width] : spec.widths.entries()) {
    const std::string key = "widths." + group;
    if (std::find(names.begin(), names.end(), group) == names.end()) {
      std::string valid;
      for (const auto& n : names)
        if (n.rfind("block", 0) != 0) valid += (valid.empty() ? "" : ", ") + n;
      for (const auto& suffix : info.block_group_suffixes)
        valid += ", block<i>_" + suffix;
      if (!info.block_group_suffixes.empty()) valid += " (i = 0.." + std::to_string(blocks - 1) + ")";
      problems.push_back({key, "unknown layer group '" + group + "' for " + spec.backbone + " x" +
                                   std::to_string(spec.scale) + " with " + std::to_string(blocks) + " blocks" +
                                   did_you_mean(group, names) + "; groups: " + valid,
                          /*at_key=*/true});
    } else if (width < 1) {
      problems.push_back({key, config::out_of_range(width, 1, config::kUnbounded)});
    }
  }
  if (spec.rit.enabled && spec.rit.channels.empty())
    problems.push_back({"rit.channels", "an enabled RIT needs at least one rendering channel"});
  std::vector<RenderChannel> rit_channels;
  try {
    rit_channels = parse_channels(spec.rit.channels);
  } catch (const Error& e) {
    problems.push_back({"rit.channels", e.message()});
  }
  try {
    parse_channels(spec.rit.feature_channels);
    for (const auto& name : spec.rit.feature_channels)
      if (std::find(spec.rit.channels.begin(), spec.rit.channels.end(), name) == spec.rit.channels.end())
        problems.push_back({"rit.feature_channels", "'" + name + "' is not among rit.channels [" +
                                                        join(spec.rit.channels) + "]: the convolutions read a subset of them"});
  } catch (const Error& e) {
    problems.push_back({"rit.feature_channels", e.message()});
  }
  if (spec.rit.width < 1)
    problems.push_back({"rit.width", config::out_of_range(spec.rit.width, 1, config::kUnbounded)});
  if (spec.rit.hr_width < 1)
    problems.push_back({"rit.hr_width", config::out_of_range(spec.rit.hr_width, 1, config::kUnbounded)});
  // The options that change the output read a channel from the raw input at the output resolution.
  const auto check_output_option = [&](bool on, const std::string& key, RenderChannel channel, const std::string& does) {
    if (!on) return;
    const std::string name = channel_name(channel), what = "rit." + key;
    const std::vector<std::string> hr_sources(rit_sources().begin() + 1, rit_sources().end());  // lr is the first
    if (!spec.rit.enabled)
      problems.push_back({what, does + " the RIT's " + name + " channel; enable rit"});
    else if (std::find(rit_channels.begin(), rit_channels.end(), channel) == rit_channels.end())
      problems.push_back({what, does + " the " + name + " channel, which rit.channels [" + join(spec.rit.channels) +
                                    "] does not list: add " + name});
    else if (!spec.rit.reads_hr())
      problems.push_back({what, "needs the " + name + " channel at the output resolution, which rit.source lr "
                                "does not give: use " + join(hr_sources, ", or ")});
  };
  check_output_option(spec.rit.bsp_composite, "bsp_composite", RenderChannel::Bsp, "composites the output with");
  const bool recurrent =
      std::find(rit_channels.begin(), rit_channels.end(), RenderChannel::HistoryOut) != rit_channels.end();
  check_output_option(spec.rit.history_blend, "history_blend", recurrent ? RenderChannel::HistoryOut : RenderChannel::History,
                      "blends the output with");
  if (spec.rit.history_warp != WarpFilter::Bilinear && !recurrent)
    problems.push_back({"rit.history_warp", "resamples the previous output, which rit.channels [" +
                                                join(spec.rit.channels) + "] does not read: add history_out"});
  if (recurrent && spec.rit.enabled && !spec.rit.reads_hr())
    problems.push_back({"rit.source", "history_out warps the previous output at the output resolution, which rit.source "
                                      "lr does not give: use an HR source"});
  if (recurrent && spec.geometry.enabled)
    problems.push_back({"geometry.enabled", "the geometry head would predict history_out, the network's own output: "
                                            "disable it"});
  check_output_option(spec.rit.skip_at_jitter, "skip_at_jitter", RenderChannel::Jitter, "takes the image skip at");
  if (spec.rit.skip_at_jitter && (!info.has_image_skip || spec.image_skip != ImageSkip::Bilinear))
    problems.push_back({"rit.skip_at_jitter", info.has_image_skip
                                                  ? "moves a bilinear image skip; image_skip is " + enum_name(spec.image_skip)
                                                  : spec.backbone + " adds no interpolated image to its output to move"});
  if (spec.rit.residual_at_jitter && !spec.rit.skip_at_jitter)
    problems.push_back({"rit.residual_at_jitter", "moves the residual over the skip that skip_at_jitter moves; set skip_at_jitter"});
  if (spec.geometry.enabled && !spec.rit.enabled)
    problems.push_back({"geometry.enabled", "the geometry head predicts the RIT's rendering channels; enable rit"});
  if (spec.geometry.width < 1)
    problems.push_back({"geometry.width", config::out_of_range(spec.geometry.width, 1, config::kUnbounded)});
  const std::string no_hr = spec.backbone + " has no HR feature map (its last layer upsamples to the image)";
  if (!info.has_hr_features && spec.rit.enabled && spec.rit.hr_branch())
    problems.push_back({"rit.source", no_hr + ", so the RIT cannot join at HR: use lr, hr_pooled or hr_unshuffle"});
  if (!info.has_hr_features && spec.geometry.enabled)
    problems.push_back({"geometry.enabled", no_hr + " for the geometry head to read"});
  return problems;
}

// The YAML node of a dotted key's value (or of the key itself), else its deepest existing ancestor.
YAML::Node locate_key(const YAML::Node& root, const std::string& key, bool at_key) {
  YAML::Node node = root;
  const auto parts = split(key, '.');
  for (size_t i = 0; i < parts.size(); ++i) {
    if (!node.IsMap()) break;
    if (at_key && i + 1 == parts.size()) {
      for (const auto& kv : node)
        if (kv.first.as<std::string>() == parts[i]) return kv.first;
      break;
    }
    const YAML::Node child = node[parts[i]];
    if (!child) break;
    node = child;
  }
  return node;
}

}  // namespace

void validate_spec(const ArchSpec& spec) {
  const auto problems = find_problems(spec);
  if (!problems.empty()) throw Error("arch spec: " + problems.front().key, problems.front().message);
  if (spec.blocks < 0) throw Error("arch spec: blocks", "unresolved (call resolve_spec)", ErrorKind::Internal);
}

ArchSpec resolve_spec(ArchSpec spec) {
  const auto problems = find_problems(spec);
  if (!problems.empty()) throw Error("arch spec: " + problems.front().key, problems.front().message);
  const BackboneInfo& info = backbone_registry().get(spec.backbone);
  if (spec.blocks < 0) spec.blocks = info.default_blocks;
  GroupWidths widths;
  for (const auto& g : info.groups(spec.scale, spec.blocks))
    widths.set(g.name, spec.widths.contains(g.name) ? spec.widths.at(g.name) : g.width);
  spec.widths = widths;
  spec.rit.channels = channel_names(parse_channels(spec.rit.channels));
  return spec;
}

ArchSpec default_spec(const std::string& backbone, int scale) {
  ArchSpec spec;
  spec.backbone = backbone;
  spec.scale = scale;
  return resolve_spec(spec);
}

std::vector<std::string> backbone_groups(const ArchSpec& spec) {
  std::vector<std::string> names;
  for (const auto& [name, width] : spec.widths.entries()) names.push_back(name);
  return names;
}

config::Schema<RitSpec> rit_spec_schema() {
  config::Schema<RitSpec> rit;
  rit.field("enabled", &RitSpec::enabled, "insert the rendering information transform block");
  rit.field("channels", &RitSpec::channels, "rendering channels the network reads (render_channels.h names)");
  rit.field("width", &RitSpec::width, "features the RIT convolution produces").at_least(1);
  rit.field("source", &RitSpec::source, "where the rendering information comes from and joins the backbone");
  rit.field("hr_width", &RitSpec::hr_width, "features of the HR branch (hr_fuse)").at_least(1);
  rit.field("fusion", &RitSpec::fusion, "how RIT features join the backbone");
  rit.field("depth_encoding", &RitSpec::depth_encoding, "how depth is encoded for the network");
  rit.field("bsp_composite", &RitSpec::bsp_composite,
            "output the bsp channel's image on the pixels its coverage marks, the network's elsewhere");
  // Written only when set, so specs and stage hashes from before the option read the same.
  rit.omit_when("bsp_composite", [](const RitSpec& r) { return !r.bsp_composite; });
  rit.field("history_blend", &RitSpec::history_blend,
            "blend the output with the history channel's samples by a learned weight where there is one");
  rit.omit_when("history_blend", [](const RitSpec& r) { return !r.history_blend; });
  rit.field("skip_at_jitter", &RitSpec::skip_at_jitter,
            "interpolate the bilinear image skip at the jitter channel's offsets (the unjittered output grid)");
  rit.omit_when("skip_at_jitter", [](const RitSpec& r) { return !r.skip_at_jitter; });
  rit.field("residual_at_jitter", &RitSpec::residual_at_jitter,
            "resample the rest of the output (over the skip) at the jitter too, at the output resolution");
  rit.omit_when("residual_at_jitter", [](const RitSpec& r) { return !r.residual_at_jitter; });
  rit.field("history_warp", &RitSpec::history_warp, "how history_out's previous output is resampled at its motion");
  rit.omit_when("history_warp", [](const RitSpec& r) { return r.history_warp == WarpFilter::Bilinear; });
  rit.field("feature_channels", &RitSpec::feature_channels,
            "the channels the RIT's convolutions read, a subset of channels (empty: all)");
  rit.omit_when("feature_channels", [](const RitSpec& r) { return r.feature_channels.empty(); });
  return rit;
}

config::Schema<GeometrySpec> geometry_spec_schema() {
  config::Schema<GeometrySpec> geometry;
  geometry.field("enabled", &GeometrySpec::enabled, "training-only head predicting HR rendering information");
  geometry.field("width", &GeometrySpec::width, "hidden width of the geometry head").at_least(1);
  return geometry;
}

config::Schema<ArchSpec> arch_spec_schema() {
  config::Schema<ArchSpec> s;
  s.field("backbone", &ArchSpec::backbone, "backbone name (" + join(backbone_registry().names()) + ")");
  s.field("scale", &ArchSpec::scale, "upscaling factor").range(2, 4);
  s.field("colors", &ArchSpec::colors, "colour channels the network works on");
  s.field("blocks", &ArchSpec::blocks, "number of residual blocks (default: the backbone's)");
  s.field("image_skip", &ArchSpec::image_skip, "interpolation of the LR image added to the output (pan)");
  // Written only when not the default, so specs and stage hashes from before the option read the same.
  s.omit_when("image_skip", [](const ArchSpec& spec) { return spec.image_skip == ImageSkip::Bilinear; });
  s.field("widths", &ArchSpec::widths, "width of each prunable layer group (default: the backbone's)");
  s.section("rit", &ArchSpec::rit, rit_spec_schema(), "rendering information transform block");
  s.section("geometry", &ArchSpec::geometry, geometry_spec_schema(), "geometry head (training only)");
  s.validate([](const ArchSpec& spec, const config::Cursor& at, const YAML::Node& node) {
    const auto problems = find_problems(spec);
    if (problems.empty()) return;
    const auto& p = problems.front();
    config::Cursor where = at;
    for (const auto& part : split(p.key, '.')) where = where.child(part);
    where.fail(locate_key(node, p.key, p.at_key), p.message);
  });
  return s;
}

ArchSpec parse_spec(const YAML::Node& node, const config::Cursor& at) {
  ArchSpec spec;
  arch_spec_schema().parse(node, spec, at);
  return resolve_spec(spec);
}

ArchSpec parse_spec(const config::Document& doc) { return parse_spec(doc.root(), config::Cursor{&doc, ""}); }

ArchSpec load_spec_file(const std::filesystem::path& path) { return parse_spec(config::Document::load_file(path)); }

ArchSpec spec_from_yaml(const std::string& text, const std::string& origin) {
  return parse_spec(config::Document::parse(text, origin));
}

YAML::Node spec_to_node(const ArchSpec& spec) { return arch_spec_schema().emit(spec); }

std::string spec_to_yaml(const ArchSpec& spec) { return config::to_yaml(spec_to_node(spec)); }

void save_spec_file(const std::filesystem::path& path, const ArchSpec& spec) {
  write_file_atomic(path, spec_to_yaml(spec));
}

std::string spec_summary(const ArchSpec& spec) {
  std::string s = spec.backbone + " x" + std::to_string(spec.scale);
  if (spec.colors == Colors::Y) s += " (Y)";
  if (spec.image_skip != ImageSkip::Bilinear) s += " (" + enum_name(spec.image_skip) + " skip)";
  if (spec.rit.enabled) {
    const auto& r = spec.rit;
    std::string widths;
    if (r.feature_branch()) widths += ", w" + std::to_string(r.width);
    if (r.hr_branch()) widths += ", hr w" + std::to_string(r.hr_width);
    s += " + rit[" + join(r.channels, "+") + widths + ", " + enum_name(r.source) + ", " + enum_name(r.fusion) + ", " + enum_name(r.depth_encoding) +
         " depth" + (r.bsp_composite ? ", bsp composite" : "") + (r.history_blend ? ", history blend" : "") +
         (r.skip_at_jitter ? (r.residual_at_jitter ? ", output at jitter" : ", skip at jitter") : "") +
         (r.history_warp != WarpFilter::Bilinear ? ", " + enum_name(r.history_warp) + " warp" : "") +
         (r.feature_channels.empty() ? "" : ", convolving " + join(r.feature_channels, "+")) + "]";
  }
  if (spec.geometry.enabled) s += " + geometry head";
  return s;
}

}  // namespace cgsr

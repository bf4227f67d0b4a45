#pragma once
// The architecture spec (the "genome"): everything needed to build a network, and everything a
// search may change. It is YAML-serializable with a config::Schema, so a spec file with a typo
// fails with file:line:col and a suggestion.
//
//   backbone: pan            # a name in the backbone registry (backbone_registry.h)
//   scale: 2                 # 2, 3 or 4
//   colors: rgb              # rgb, or y (SRCNN only: the network sees BT.601 luma)
//   blocks: 16               # residual blocks (PAN, EDSR); 0 for SRCNN
//   image_skip: bilinear     # PAN: the interpolation of the LR image added to the output
//                            #   (bilinear, PAN's own; bicubic leaves the network less to learn)
//   widths:                  # width of every prunable layer group, by name
//     features: 40
//     block0_a: 20
//     ...
//   rit:                     # rendering information transform (rit.h)
//     enabled: true
//     channels: [depth, normal, normal_angle, edge]
//     width: 16
//     source: lr             # where the information comes from and where it joins (rit.h):
//                            #   lr, hr_pooled, hr_unshuffle, hr_fuse, hr_unshuffle+hr_fuse
//     hr_width: 16           # features of the HR branch (hr_fuse; layer group "rit_hr")
//     fusion: concat         # concat (feat + 1x1(cat(feat, rit))), or add (feat + 1x1(rit))
//     depth_encoding: log    # log, linear or zbuffer (render_channels.h DepthEncoding)
//     bsp_composite: false   # the output is the bsp channel's image where its coverage is 1,
//                            #   the network's elsewhere (needs bsp among channels, an HR source)
//     history_blend: false   # the output blended with the history channel's samples by a learned
//                            #   weight (needs history among channels, an HR source); with
//                            #   history_out among them (the network's own previous output,
//                            #   warped: a recurrent network, HR sources only), with that
//     skip_at_jitter: false  # PAN's bilinear image skip taken at the jitter channel's offsets
//                            #   (needs jitter among channels, an HR source)
//     residual_at_jitter: false  # the rest of the output moved to the jitter as well, at HR
//                            #   (needs skip_at_jitter)
//     history_warp: bilinear # how history_out's previous output is resampled at its motion:
//                            #   bilinear, or bicubic (sharper; needs history_out)
//     feature_channels: []   # the channels the RIT's convolutions read (a subset of channels;
//                            #   empty: all). The rest reach only the options that use them
//                            #   (jitter the skip, history_out the warp and the blend)
//   geometry:                # training-only head predicting the HR rendering information
//     enabled: true
//     width: 16
//
// A layer group is a set of channels that must be kept or removed together: the outputs of
// every layer writing into one residual stream, both operands of an attention product, the r*r
// sub-pixel channels of a pixel shuffle. Widths are given per group, so a spec cannot describe
// an inconsistent network; the group names of each backbone are listed by backbone_groups().
// Missing `blocks` and `widths` entries take the backbone's defaults when parsed; a resolved
// spec lists every group in the backbone's order.

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "core/config.h"
#include "render_data/render_channels.h"

namespace cgsr {

// Width per layer group, in the backbone's canonical order.
class GroupWidths {
 public:
  int at(const std::string& group) const;  // Error naming the group when absent
  bool contains(const std::string& group) const;
  void set(const std::string& group, int width);  // appends unknown groups
  const std::vector<std::pair<std::string, int>>& entries() const { return entries_; }
  bool empty() const { return entries_.empty(); }
  bool operator==(const GroupWidths& o) const { return entries_ == o.entries_; }
  bool operator!=(const GroupWidths& o) const { return !(*this == o); }

 private:
  std::vector<std::pair<std::string, int>> entries_;
};

// Where the rendering information comes from and where it joins the backbone (rit.h); spelled
// lr, hr_pooled, hr_unshuffle, hr_fuse, hr_unshuffle+hr_fuse in specs and model files.
enum class RitSource { Lr, HrPooled, HrUnshuffle, HrFuse, HrUnshuffleHrFuse };
template <>
struct EnumNames<RitSource> {
  static constexpr const char* kind = "rit source";
  static const std::vector<std::string>& names();
};

// How RIT features join the backbone: concat (feat + 1x1(cat(feat, rit))) or add (feat + 1x1(rit)).
enum class RitFusion { Concat, Add };
template <>
struct EnumNames<RitFusion> {
  static constexpr const char* kind = "rit fusion";
  static const std::vector<std::string>& names();
};

// How a recurrent network's previous output is resampled when warped to the current frame (rit.h):
// bilinear, or bicubic (a = -0.75, sharper: a bilinear warp blurs what it carries, every frame).
enum class WarpFilter { Bilinear, Bicubic };
template <>
struct EnumNames<WarpFilter> {
  static constexpr const char* kind = "history warp";
  static const std::vector<std::string>& names();
};

// The colour channels a network works on: rgb, or y (BT.601 luma; SRCNN only).
enum class Colors { Rgb, Y };
template <>
struct EnumNames<Colors> {
  static constexpr const char* kind = "colors";
  static const std::vector<std::string>& names();
};

// The interpolation of the LR image a backbone adds to its output (PAN): bilinear or bicubic.
enum class ImageSkip { Bilinear, Bicubic };
template <>
struct EnumNames<ImageSkip> {
  static constexpr const char* kind = "image skip";
  static const std::vector<std::string>& names();
};

struct RitSpec {
  bool enabled = false;
  std::vector<std::string> channels = {"depth", "normal", "normal_angle", "edge"};  // render_channels.h names
  int width = 16;                 // features the RIT convolution produces (layer group "rit")
  RitSource source = RitSource::Lr;
  int hr_width = 16;              // features of the HR branch (layer group "rit_hr")
  RitFusion fusion = RitFusion::Concat;
  DepthEncoding depth_encoding = DepthEncoding::Log;  // log, linear or zbuffer in YAML
  // The network's image composited with the bsp channel at HR (rit.h): out = (1 - m) * net + m *
  // bsp_rgb, m the channel's coverage. Where the renderer resolved the border (the BSP leaves) the
  // output is its image exactly; the network learns the rest.
  bool bsp_composite = false;
  // The network's image blended with the history channel's reprojected samples at HR (rit.h):
  // out = net + w * (history_rgb - net), w = sigmoid(conv(net, info)) * recency. Where no frame
  // left a sample (recency 0) the output is the network's; elsewhere it learns how far to trust one.
  bool history_blend = false;
  // PAN's bilinear image skip interpolated at the frame's jitter (the jitter channel, rit.h): the
  // output pixel's own position in a jittered LR frame, where the unjittered skip reads it up to
  // half an LR pixel off.
  bool skip_at_jitter = false;
  // With skip_at_jitter, the rest of the output too (the network's residual over its skip): the
  // backbone reads the jittered frame as if aligned, so its detail sits s * jitter HR pixels off;
  // it is resampled there at HR (rit.h).
  bool residual_at_jitter = false;
  // history_out's warp of the previous output (rit.h).
  WarpFilter history_warp = WarpFilter::Bilinear;
  // The channels the RIT's convolutions read, a subset of `channels`; empty: all of them. Jitter
  // and the previous output pay through the skip and the blend, which read the raw input anyway;
  // at 4x the convolutions reading them too cost 6.5 % more MACs (11.26 against 10.57 G).
  std::vector<std::string> feature_channels;

  std::vector<RenderChannel> render_channels() const { return parse_channels(channels); }
  std::vector<RenderChannel> convolved_channels() const {
    return feature_channels.empty() ? render_channels() : parse_channels(feature_channels);
  }
  int info_width() const { return total_width(render_channels()); }
  // The parts the source asks for: the block at the backbone's feature map (lr, hr_pooled,
  // hr_unshuffle) and the branch at the HR features (hr_fuse).
  bool feature_branch() const { return source != RitSource::HrFuse; }
  bool hr_branch() const { return source == RitSource::HrFuse || source == RitSource::HrUnshuffleHrFuse; }
  bool unshuffles() const { return source == RitSource::HrUnshuffle || source == RitSource::HrUnshuffleHrFuse; }
  // Every source except lr reads the rendering information at the output resolution.
  bool reads_hr() const { return source != RitSource::Lr; }
  bool operator==(const RitSpec& o) const {
    return enabled == o.enabled && channels == o.channels && width == o.width && source == o.source &&
           hr_width == o.hr_width && fusion == o.fusion && depth_encoding == o.depth_encoding &&
           bsp_composite == o.bsp_composite && history_blend == o.history_blend && skip_at_jitter == o.skip_at_jitter &&
           residual_at_jitter == o.residual_at_jitter && history_warp == o.history_warp &&
           feature_channels == o.feature_channels;
  }
};

// The names of rit.source, in the order ablations list them.
inline const std::vector<std::string>& rit_sources() { return EnumNames<RitSource>::names(); }

struct GeometrySpec {
  bool enabled = false;
  int width = 16;  // hidden width of the geometry head (layer group "geometry")
  bool operator==(const GeometrySpec& o) const { return enabled == o.enabled && width == o.width; }
};

struct ArchSpec {
  std::string backbone = "pan";
  int scale = 2;
  Colors colors = Colors::Rgb;
  int blocks = -1;             // -1 until resolved: the backbone's default
  ImageSkip image_skip = ImageSkip::Bilinear;  // backbones with an image skip (BackboneInfo)
  GroupWidths widths;
  RitSpec rit;
  GeometrySpec geometry;

  // Width of any layer group: backbone groups, "rit", "rit_hr" and "geometry".
  int group_width(const std::string& group) const;
  void set_group_width(const std::string& group, int width);
  // Rendering channels the network takes as input (empty without RIT).
  std::vector<RenderChannel> input_channels() const;
  int color_channels() const { return colors == Colors::Y ? 1 : 3; }

  bool operator==(const ArchSpec& o) const {
    return backbone == o.backbone && scale == o.scale && colors == o.colors && blocks == o.blocks &&
           image_skip == o.image_skip && widths == o.widths && rit == o.rit && geometry == o.geometry;
  }
  bool operator!=(const ArchSpec& o) const { return !(*this == o); }
};

// The default spec of a backbone at a scale: the published architecture, no RIT, no head.
ArchSpec default_spec(const std::string& backbone, int scale);

// The layer groups of a (resolved) spec's backbone, in canonical order, without rit/geometry.
std::vector<std::string> backbone_groups(const ArchSpec& spec);

// Fills `blocks`, missing widths (defaults) and puts widths and rit.channels in canonical order.
// Then validates. Throws Error("arch spec", ...) naming the offending key.
ArchSpec resolve_spec(ArchSpec spec);
void validate_spec(const ArchSpec& spec);

// Schema binding for YAML; parse_spec() = parse + resolve + validate, errors at file:line:col.
config::Schema<ArchSpec> arch_spec_schema();
config::Schema<RitSpec> rit_spec_schema();
config::Schema<GeometrySpec> geometry_spec_schema();
ArchSpec parse_spec(const config::Document& doc);
ArchSpec parse_spec(const YAML::Node& node, const config::Cursor& at);  // a spec nested in another config
ArchSpec load_spec_file(const std::filesystem::path& path);
ArchSpec spec_from_yaml(const std::string& text, const std::string& origin);
YAML::Node spec_to_node(const ArchSpec& spec);
std::string spec_to_yaml(const ArchSpec& spec);
void save_spec_file(const std::filesystem::path& path, const ArchSpec& spec);  // atomic

// "pan x2 + rit[depth+edge, w16, lr, concat]" for logs, tables and error contexts.
std::string spec_summary(const ArchSpec& spec);

namespace config {
template <>
struct Codec<GroupWidths> {
  static GroupWidths decode(const YAML::Node& node, const Cursor& at);
  static YAML::Node encode(const GroupWidths& widths);
};
}  // namespace config

}  // namespace cgsr

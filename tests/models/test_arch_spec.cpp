// The architecture spec: defaults, YAML round trips, and validation errors that point at the
// offending key with file:line:col.
#include <gtest/gtest.h>

#include "core/error.h"
#include "models/arch_spec.h"
#include "models/backbone_registry.h"
#include "tests/models/model_cases.h"
#include "tests/support/scratch_dir.h"

using namespace cgsr;
using namespace cgsr::test;

namespace {
std::string parse_error(const std::string& yaml) {
  try {
    spec_from_yaml(yaml, "spec.yaml");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(ArchSpec, DefaultsListEveryGroupInOrder) {
  const ArchSpec pan = default_spec("pan", 4);
  EXPECT_EQ(pan.blocks, 16);
  EXPECT_EQ(pan.widths.entries().size(), 1u + 16 * 5 + 4);
  EXPECT_EQ(pan.widths.entries().front(), (std::pair<std::string, int>{"features", 40}));
  EXPECT_EQ(pan.widths.at("block15_b_out"), 20);
  EXPECT_EQ(pan.widths.at("hr2"), 24);
  EXPECT_FALSE(default_spec("pan", 2).widths.contains("up2"));
  const ArchSpec srcnn = default_spec("srcnn", 3);
  EXPECT_EQ(srcnn.blocks, 0);
  EXPECT_EQ(backbone_groups(srcnn), (std::vector<std::string>{"conv1", "conv2"}));
  EXPECT_EQ(default_spec("edsr", 2).group_width("block7_mid"), 64);
}

TEST(ArchSpec, YamlRoundTripForEveryBackbone) {
  for (const auto& c : all_backbone_cases()) {
    SCOPED_TRACE(case_name(c));
    for (bool rit : {false, true}) {
      ArchSpec s = rit ? with_rit(spec_for(c), "hr_pooled", "add", cgsr::test::has_hr_features(c.backbone)) : spec_for(c);
      if (rit) {
        s.rit.width = 7;
        s.widths.set(backbone_groups(s).back(), 3);
      }
      const ArchSpec back = spec_from_yaml(spec_to_yaml(s), "roundtrip");
      EXPECT_EQ(back, s) << spec_to_yaml(s);
    }
  }
}

TEST(ArchSpec, FilesRoundTripAtomically) {
  const auto dir = test::scratch_dir("spec");
  ArchSpec s = with_rit(default_spec("edsr", 4));
  s.blocks = 5;
  s.widths = GroupWidths();
  s = resolve_spec(s);
  save_spec_file(dir / "edsr.yaml", s);
  EXPECT_EQ(load_spec_file(dir / "edsr.yaml"), s);
  std::filesystem::remove_all(dir);
}

TEST(ArchSpec, PartialSpecsTakeBackboneDefaults) {
  const ArchSpec s = spec_from_yaml("backbone: pan\nscale: 3\nblocks: 4\nwidths: {features: 32, block2_att: 8}\n"
                                    "rit: {enabled: true, channels: [edge, depth]}\n",
                                    "partial");
  EXPECT_EQ(s.blocks, 4);
  EXPECT_EQ(s.widths.at("features"), 32);
  EXPECT_EQ(s.widths.at("block2_att"), 8);
  EXPECT_EQ(s.widths.at("block2_a"), 20);
  EXPECT_EQ(s.widths.at("up1"), 24);
  EXPECT_EQ(s.widths.entries().front().first, "features");  // canonical order, not file order
  EXPECT_EQ(s.rit.channels, (std::vector<std::string>{"depth", "edge"}));
  EXPECT_EQ(s.rit.info_width(), 2);
}

TEST(ArchSpec, TyposPointAtFileLineAndColumn) {
  std::string e = parse_error("backbone: pan\nwidhts: {features: 32}\n");
  EXPECT_NE(e.find("spec.yaml:2:1"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'widths'"), std::string::npos) << e;

  e = parse_error("backbone: pan\nwidths:\n  featurs: 32\n");
  EXPECT_NE(e.find("spec.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'features'"), std::string::npos) << e;

  e = parse_error("backbone: pan\nblocks: 2\nwidths:\n  block5_a: 8\n");
  EXPECT_NE(e.find("spec.yaml:4:"), std::string::npos) << e;
  EXPECT_NE(e.find("with 2 blocks"), std::string::npos) << e;

  e = parse_error("backbone: edsr\nwidths:\n  up1: 0\n");
  EXPECT_NE(e.find("spec.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("widths.up1: '0' is out of range [1, inf)"), std::string::npos) << e;

  e = parse_error("backbone: edsr\nwidths:\n  up1: wide\n");
  EXPECT_NE(e.find("expected an integer"), std::string::npos) << e;

  e = parse_error("backbone: pam\n");
  EXPECT_NE(e.find("spec.yaml:1:"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'pan'"), std::string::npos) << e;

  e = parse_error("backbone: pan\nrit:\n  enabled: true\n  channels: [dpeth]\n");
  EXPECT_NE(e.find("spec.yaml:4:"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'depth'"), std::string::npos) << e;

  e = parse_error("backbone: pan\nrit: {enabled: true, fusion: concatenate}\n");
  EXPECT_NE(e.find("not one of: concat, add"), std::string::npos) << e;

  e = parse_error("backbone: pan\nrit:\n  enabled: true\n  depth_encoding: logg\n");
  EXPECT_NE(e.find("spec.yaml:4:"), std::string::npos) << e;
  EXPECT_NE(e.find("rit.depth_encoding"), std::string::npos) << e;
  EXPECT_NE(e.find("'logg' is not one of: log, linear, zbuffer"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'log'"), std::string::npos) << e;
}

// rit.depth_encoding is an enum in code and its name in YAML: each spelling reads back as itself.
TEST(ArchSpec, DepthEncodingIsParsedOnceAndWrittenByName) {
  for (const auto& name : EnumNames<DepthEncoding>::names()) {
    const ArchSpec s = spec_from_yaml("backbone: pan\nrit: {enabled: true, depth_encoding: " + name + "}\n", "spec");
    EXPECT_EQ(enum_name(s.rit.depth_encoding), name);
    EXPECT_NE(spec_to_yaml(s).find("depth_encoding: " + name + "\n"), std::string::npos) << spec_to_yaml(s);
  }
  EXPECT_EQ(default_spec("pan", 2).rit.depth_encoding, DepthEncoding::Log);
}

TEST(ArchSpec, InconsistentCombinationsAreErrors) {
  EXPECT_NE(parse_error("backbone: pan\ncolors: y\n").find("srcnn"), std::string::npos);
  EXPECT_NE(parse_error("backbone: srcnn\nblocks: 3\n").find("no residual blocks"), std::string::npos);
  EXPECT_NE(parse_error("backbone: pan\nscale: 5\n").find("scale: '5' is out of range [2, 4]"), std::string::npos);
  EXPECT_NE(parse_error("backbone: pan\ngeometry: {enabled: true}\n").find("enable rit"), std::string::npos);
  EXPECT_NE(parse_error("backbone: pan\nrit: {enabled: true, channels: []}\n").find("at least one"),
            std::string::npos);
  EXPECT_NE(parse_error("backbone: pan\nwidths: {features: 0}\n").find("widths.features: '0' is out of range [1, inf)"),
            std::string::npos);
  EXPECT_NE(parse_error("backbone: edsr\nblocks: 0\n").find("blocks: '0' is out of range [1, 64]"), std::string::npos);
  EXPECT_NE(parse_error("backbone: edsr\nimage_skip: bicubic\n").find("image_skip is for pan"), std::string::npos);
  EXPECT_NE(parse_error("backbone: pan\nimage_skip: bicubc\n").find("did you mean 'bicubic'"), std::string::npos);
}

// The option is written only when set, so specs (and stage hashes) from before it read the same.
TEST(ArchSpec, ImageSkipRoundTripsAndIsOmittedAtItsDefault) {
  ArchSpec s = default_spec("pan", 2);
  EXPECT_EQ(spec_to_yaml(s).find("image_skip"), std::string::npos);
  s.image_skip = ImageSkip::Bicubic;
  const std::string yaml = spec_to_yaml(s);
  EXPECT_NE(yaml.find("image_skip: bicubic"), std::string::npos) << yaml;
  EXPECT_EQ(spec_from_yaml(yaml, "roundtrip"), s);
  EXPECT_NE(spec_summary(s).find("bicubic skip"), std::string::npos);
}

TEST(ArchSpec, ProgrammaticSpecsAreValidatedToo) {
  ArchSpec s = default_spec("pan", 2);
  s.widths.set("features", -3);
  try {
    validate_spec(s);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.context(), "arch spec: widths.features");
  }
  EXPECT_THROW(resolve_spec(s), Error);
}

// rit.bsp_composite, rit.history_blend and rit.skip_at_jitter read their channel at HR: without
// the channel, with rit.source lr or without a RIT it is an error naming the key; each is written
// only when set. skip_at_jitter moves PAN's bilinear skip: another backbone or skip is an error.
TEST(ArchSpec, CompositesNeedTheirChannelAtHr) {
  struct Composite {
    std::string key, channel, summary;
    bool RitSpec::*flag;
  };
  for (const Composite& c : {Composite{"bsp_composite", "bsp", "bsp composite", &RitSpec::bsp_composite},
                             Composite{"history_blend", "history", "history blend", &RitSpec::history_blend},
                             Composite{"skip_at_jitter", "jitter", "skip at jitter", &RitSpec::skip_at_jitter}}) {
    SCOPED_TRACE(c.key);
    const std::string key = "rit." + c.key;
    const std::string missing = parse_error("backbone: pan\nrit: {enabled: true, channels: [depth, edge], source: hr_fuse, " +
                                            c.key + ": true}\n");
    EXPECT_NE(missing.find(key), std::string::npos) << missing;
    EXPECT_NE(missing.find("does not list: add " + c.channel), std::string::npos) << missing;
    const std::string lr =
        parse_error("backbone: pan\nrit: {enabled: true, channels: [" + c.channel + "], " + c.key + ": true}\n");
    EXPECT_NE(lr.find(key), std::string::npos) << lr;
    EXPECT_NE(lr.find("rit.source lr"), std::string::npos) << lr;
    EXPECT_NE(lr.find("hr_unshuffle+hr_fuse"), std::string::npos) << lr;
    const std::string off =
        parse_error("backbone: pan\nrit: {channels: [" + c.channel + "], source: hr_fuse, " + c.key + ": true}\n");
    EXPECT_NE(off.find(key), std::string::npos) << off;
    EXPECT_NE(off.find("enable rit"), std::string::npos) << off;

    ArchSpec s = default_spec("pan", 2);
    s.rit.enabled = true;
    s.rit.channels = {c.channel};
    s.rit.source = RitSource::HrFuse;
    EXPECT_EQ(spec_to_yaml(s).find(c.key), std::string::npos);
    s.rit.*c.flag = true;
    const std::string yaml = spec_to_yaml(s);
    EXPECT_NE(yaml.find(c.key + ": true"), std::string::npos) << yaml;
    EXPECT_EQ(spec_from_yaml(yaml, "roundtrip"), s);
    EXPECT_NE(spec_summary(s).find(c.summary), std::string::npos) << spec_summary(s);
    s.rit.source = RitSource::Lr;
    try {
      validate_spec(s);
      FAIL();
    } catch (const Error& e) {
      EXPECT_EQ(e.context(), "arch spec: " + key);
    }
  }
  for (const std::string& other : std::vector<std::string>{"backbone: edsr", "backbone: pan\nimage_skip: bicubic"}) {
    const std::string error = parse_error(other + "\nrit: {enabled: true, channels: [jitter], source: hr_fuse, skip_at_jitter: true}\n");
    EXPECT_NE(error.find("rit.skip_at_jitter"), std::string::npos) << error;
    EXPECT_NE(error.find(other == "backbone: edsr" ? "adds no interpolated image" : "image_skip is bicubic"), std::string::npos)
        << error;
  }
  // residual_at_jitter moves the residual over the moved skip: without skip_at_jitter it is an error.
  const std::string alone = parse_error(
      "backbone: pan\nrit: {enabled: true, channels: [jitter], source: hr_fuse, residual_at_jitter: true}\n");
  EXPECT_NE(alone.find("rit.residual_at_jitter"), std::string::npos) << alone;
  EXPECT_NE(alone.find("set skip_at_jitter"), std::string::npos) << alone;
}

// rit.history_warp resamples history_out's previous output: without that channel it is an error
// naming the key; written only when not bilinear; a misspelt filter names the choices.
TEST(ArchSpec, HistoryWarpNeedsThePreviousOutput) {
  const std::string unread =
      parse_error("backbone: pan\nrit: {enabled: true, channels: [edge], source: hr_fuse, history_warp: bicubic}\n");
  EXPECT_NE(unread.find("rit.history_warp"), std::string::npos) << unread;
  EXPECT_NE(unread.find("add history_out"), std::string::npos) << unread;
  const std::string misspelt =
      parse_error("backbone: pan\nrit: {enabled: true, channels: [history_out], source: hr_fuse, history_warp: cubic}\n");
  EXPECT_NE(misspelt.find("bilinear, bicubic"), std::string::npos) << misspelt;
  ArchSpec s = default_spec("pan", 2);
  s.rit.enabled = true;
  s.rit.channels = {"history_out"};
  s.rit.source = RitSource::HrFuse;
  EXPECT_EQ(spec_to_yaml(s).find("history_warp"), std::string::npos);
  s.rit.history_warp = WarpFilter::Bicubic;
  const std::string yaml = spec_to_yaml(s);
  EXPECT_NE(yaml.find("history_warp: bicubic"), std::string::npos) << yaml;
  EXPECT_EQ(spec_from_yaml(yaml, "roundtrip"), s);
  EXPECT_NE(spec_summary(s).find("bicubic warp"), std::string::npos) << spec_summary(s);
}

// rit.feature_channels: a channel the RIT does not read is an error naming the key and the
// channels; written only when set, and read back the same.
TEST(ArchSpec, FeatureChannelsAreASubsetOfTheChannels) {
  const std::string unread =
      parse_error("backbone: pan\nrit: {enabled: true, channels: [edge], source: hr_fuse, feature_channels: [depth]}\n");
  EXPECT_NE(unread.find("rit.feature_channels"), std::string::npos) << unread;
  EXPECT_NE(unread.find("'depth' is not among rit.channels [edge]"), std::string::npos) << unread;
  const std::string twice =
      parse_error("backbone: pan\nrit: {enabled: true, channels: [edge], source: hr_fuse, feature_channels: [edge, edge]}\n");
  EXPECT_NE(twice.find("rit.feature_channels"), std::string::npos) << twice;
  EXPECT_NE(twice.find("listed twice"), std::string::npos) << twice;
  ArchSpec s = default_spec("pan", 2);
  s.rit.enabled = true;
  s.rit.channels = {"edge", "jitter"};
  s.rit.source = RitSource::HrFuse;
  EXPECT_EQ(spec_to_yaml(s).find("feature_channels"), std::string::npos);
  s.rit.feature_channels = {"edge"};
  const std::string yaml = spec_to_yaml(s);
  EXPECT_NE(yaml.find("feature_channels"), std::string::npos) << yaml;
  EXPECT_EQ(spec_from_yaml(yaml, "roundtrip"), s);
  EXPECT_NE(spec_summary(s).find("convolving edge"), std::string::npos) << spec_summary(s);
}

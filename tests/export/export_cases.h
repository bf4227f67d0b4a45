#pragma once
// Fixtures of the export tests: the networks every format must export and verify (every
// backbone at every scale, CG-enhanced variants, shrunk specs as search and pruning produce),
// built with weights that make every branch matter.

#include <torch/torch.h>

#include <string>
#include <vector>

#include "models/sr_network.h"
#include "tests/models/model_cases.h"

namespace cgsr::test {

struct ExportCase {
  std::string name;  // also a file stem: letters, digits, '_'
  ArchSpec spec;
};

// A spec with smaller, uneven widths and fewer blocks: what static pruning and the search produce.
inline ArchSpec shrunk_pan(int scale) {
  ArchSpec s = default_spec("pan", scale);
  s.blocks = 2;
  s.widths = GroupWidths();
  s.widths.set("features", 24);
  s.widths.set("block0_a", 7);
  s.widths.set("block0_a_out", 9);
  s.widths.set("block0_b", 5);
  s.widths.set("block0_att", 11);
  s.widths.set("block0_b_out", 6);
  s.widths.set("block1_a", 12);
  s.widths.set("block1_b_out", 3);
  s.widths.set("up1", 10);
  s.widths.set("hr1", 13);
  return resolve_spec(s);
}

inline ArchSpec shrunk_edsr(int scale) {
  ArchSpec s = default_spec("edsr", scale);
  s.blocks = 3;
  s.widths = GroupWidths();
  s.widths.set("features", 20);
  s.widths.set("block0_mid", 9);
  s.widths.set("block2_mid", 30);
  s.widths.set("up1", 7);
  return resolve_spec(s);
}

inline std::string stem(const BackboneCase& c) {
  return c.backbone + "_x" + std::to_string(c.scale) + (c.colors == "y" ? "_y" : "");
}

// Every backbone at every scale (SRCNN in RGB and Y), then CG-enhanced and shrunk networks.
inline std::vector<ExportCase> export_cases() {
  std::vector<ExportCase> cases;
  for (const auto& c : all_backbone_cases()) cases.push_back({stem(c), spec_for(c)});
  cases.push_back({"pan_x2_rit_lr_concat", with_rit(default_spec("pan", 2), "lr", "concat")});
  cases.push_back({"edsr_x3_rit_hr_pooled_add", with_rit(default_spec("edsr", 3), "hr_pooled", "add")});
  cases.push_back({"srcnn_x2_rit_lr_add", with_rit(default_spec("srcnn", 2), "lr", "add")});
  cases.push_back({"pan_x4_rit_hr_pooled_concat_geometry",
                   with_rit(default_spec("pan", 4), "hr_pooled", "concat", /*geometry=*/true)});
  cases.push_back({"shrunk_pan_x2_rit", with_rit(shrunk_pan(2), "lr", "concat")});
  cases.push_back({"pan_x2_rit_hr_unshuffle_concat", with_rit(default_spec("pan", 2), "hr_unshuffle", "concat")});
  cases.push_back({"pan_x4_rit_hr_fuse_concat", with_rit(default_spec("pan", 4), "hr_fuse", "concat")});
  cases.push_back({"edsr_x2_rit_hr_unshuffle_hr_fuse_add",
                   with_rit(default_spec("edsr", 2), "hr_unshuffle+hr_fuse", "add")});
  cases.push_back({"srcnn_x3_rit_hr_fuse_concat", with_rit(default_spec("srcnn", 3), "hr_fuse", "concat")});
  cases.push_back({"shrunk_edsr_x4", shrunk_edsr(4)});
  cases.push_back({"span_x2_rit_hr_unshuffle_concat", with_rit(default_spec("span", 2), "hr_unshuffle", "concat")});
  // CG-enhanced SRPO: the RIT at its LR features and its HR features (after the upsampling).
  cases.push_back({"srpo_x2_rit_hr_unshuffle_hr_fuse_concat",
                   with_rit(default_spec("srpo", 2), "hr_unshuffle+hr_fuse", "concat")});
  ArchSpec bicubic_skip = default_spec("pan", 3);
  bicubic_skip.image_skip = ImageSkip::Bicubic;
  cases.push_back({"pan_x3_bicubic_skip", bicubic_skip});
  return cases;
}

}  // namespace cgsr::test

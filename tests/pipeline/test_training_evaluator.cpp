// The search's real evaluator (pipeline/training_evaluator.h) on the tiny scene: fade, inheritance
// (of the blocks the parent's block importance spares) and training of a candidate give a finite score, and the parent is scored as the candidate
// equal to it, so the pick rule compares networks that trained alike.
#include <gtest/gtest.h>

#include <cmath>

#include "core/runtime.h"
#include "models/arch_spec.h"
#include "models/importance/block_importance.h"
#include "pipeline/training_evaluator.h"
#include "search/search_space.h"
#include "tests/support/tiny_data.h"

namespace cgsr {
namespace {

ArchSpec parent_spec() {
  return spec_from_yaml("backbone: pan\nscale: 2\nblocks: 2\n"
                        "rit: {enabled: true, channels: [depth, normal, edge], width: 8}\n",
                        "test");
}

CandidateTraining short_training() {
  CandidateTraining t;
  t.fade_steps = 3;
  t.schedule.steps = 4;
  t.schedule.batch_size = 2;
  t.schedule.patch_size = 16;
  t.schedule.validate_every = 0;
  t.schedule.val_frames = 1;
  return t;
}

TEST(TrainingEvaluator, TheParentIsScoredAsTheCandidateEqualToIt) {
  set_threads(1);
  seed_everything(5);
  const SRNetwork parent(parent_spec());
  const Dataset data = Dataset::open(test::tiny_data());
  TrainingEvaluator evaluator(parent, data, short_training(), block_drop_order(*parent));

  // A narrower, shallower candidate: faded (its dropped block whole), cut and trained.
  SearchSpaceOptions space_options;
  space_options.min_blocks = 1;
  const SearchSpace space(parent->spec(), space_options, evaluator.block_drop_order());
  std::mt19937_64 rng(7);
  ArchSpec child = space.mutate(parent->spec(), 1.0, rng);
  for (int tries = 0; child.blocks != 1 && tries < 50; ++tries) child = space.mutate(parent->spec(), 1.0, rng);
  ASSERT_EQ(child.blocks, 1);
  EXPECT_EQ(evaluator.parent_blocks(child), space.parent_blocks(child));
  const CandidateScore c = evaluator.evaluate(child);
  EXPECT_TRUE(std::isfinite(c.val_psnr)) << c.val_psnr;
  EXPECT_GT(c.val_psnr, 5);
  EXPECT_GT(c.train_seconds, 0);

  // The parent's score is the unchanged candidate's, bit for bit, and it trained: it differs
  // from the parent validated as it stands.
  const CandidateScore as_candidate = evaluator.evaluate(parent->spec());
  const CandidateScore as_parent = evaluator.evaluate_parent();
  EXPECT_EQ(as_parent.val_psnr, as_candidate.val_psnr);
  EXPECT_EQ(as_parent.params, as_candidate.params);
  EXPECT_LT(c.params, as_parent.params);
  Trainer untrained(parent, data, short_training().schedule, short_training().loss);
  EXPECT_NE(as_parent.val_psnr, untrained.validate(0).psnr);
  // The parent network itself is not changed by being scored.
  EXPECT_EQ(untrained.validate(0).psnr, Trainer(parent, data, short_training().schedule, short_training().loss).validate(0).psnr);
}

}  // namespace
}  // namespace cgsr

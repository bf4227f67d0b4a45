// The worked examples of docs/extending.md, built and run: the example backbone, the box scene
// source, the hill-climbing search strategy and the activation importance criterion
// (tests/extending/example_*.cpp), each registered the way the page says. The page quotes those
// files, and the last test checks that it quotes them to the letter.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>

#include "core/error.h"
#include "core/runtime.h"
#include "models/backbone_registry.h"
#include "models/complexity.h"
#include "models/elastic.h"
#include "models/fused_graph.h"
#include "models/importance/channel_importance.h"
#include "models/model_file.h"
#include "render_data/dataset.h"
#include "render_data/render_job.h"
#include "render_data/scene_source.h"
#include "search/search_loop.h"
#include "tests/models/model_cases.h"
#include "tests/support/tiny_data.h"
#include "train/trainer.h"

namespace cgsr {
// What the example files define.
void register_backbone_example(Registry<BackboneInfo>& registry);
void register_box_scene_source(Registry<SceneSourceFactory>& registry);
void register_hill_climb_strategy(Registry<StrategyType>& registry);
FrameImportance activation_importance(const SRNetworkImpl& net, const torch::Tensor& color, const torch::Tensor& info);
}  // namespace cgsr

using namespace cgsr;
using namespace cgsr::test;
namespace fs = std::filesystem;

namespace {

// A program that embeds cgsr adds its entries to the process-wide registries once, before it
// parses configs or builds networks.
void register_examples() {
  static const bool registered = [] {
    register_backbone_example(backbone_registry());
    register_box_scene_source(scene_sources());
    register_hill_climb_strategy(strategy_registry());
    return true;
  }();
  (void)registered;
}

ArchSpec example_spec(int blocks, const std::string& extra = "") {
  return spec_from_yaml("backbone: example\nscale: 2\nblocks: " + std::to_string(blocks) + "\n" + extra, "example.yaml");
}

fs::path fresh_dir(const std::string& name) { return test::scratch_dir("extending-" + name); }

// Widths in steps of 4 down to a quarter, at least `min_blocks` blocks.
ElasticOptions elastic_options(int min_blocks) {
  ElasticOptions options;
  options.min_blocks = min_blocks;
  return options;
}

double largest_difference(const torch::Tensor& a, const torch::Tensor& b) { return (a - b).abs().max().item<double>(); }

}  // namespace

TEST(ExtendingBackbone, TheToyIsBuiltByNameAtEveryScaleAndItsGraphIsItsForward) {
  register_examples();
  const auto names = backbone_registry().names();
  EXPECT_NE(std::find(names.begin(), names.end(), "example"), names.end());
  for (int scale : {2, 3, 4})
    for (const char* source : {"", "lr", "hr_unshuffle+hr_fuse"}) {
      SCOPED_TRACE("x" + std::to_string(scale) + " " + source);
      ArchSpec spec = default_spec("example", scale);
      if (*source) spec = with_rit(spec, source, "concat", /*geometry=*/true);
      expect_graph_matches_forward(spec);
      SRNetwork net(spec);
      // Complexity counting sees every parameter of the inference network through the graph.
      EXPECT_EQ(complexity(*net, 8, 8).params, inference_parameter_count(*net));
    }
}

TEST(ExtendingBackbone, TheToyTrainsRunsOnTheFusedPathAndRoundTripsAModelFile) {
  register_examples();
  set_threads(1);
  seed_everything(5);
  SRNetwork net(example_spec(3, "rit: {enabled: true, channels: [depth, edge]}\n"));
  const auto before = net->parameters()[0].detach().clone();
  TrainSchedule schedule;
  schedule.steps = 2;
  schedule.batch_size = 2;
  schedule.patch_size = 16;
  schedule.val_frames = 1;
  schedule.layout = MemoryLayout::Nchw;
  const Dataset data = Dataset::open(tiny_data());
  const TrainOutcome outcome = Trainer(net, data, schedule, LossOptions{}).run();
  EXPECT_EQ(outcome.steps, 2);
  EXPECT_TRUE(std::isfinite(outcome.best.psnr));
  EXPECT_FALSE(torch::equal(before, net->parameters()[0]));

  randomize_fusion(*net);
  net->eval();
  const auto [color, info] = random_inputs(net->spec(), 20, 12);
  torch::NoGradGuard no_grad;
  const auto expected = net->forward(color, info);
  FusedGraph fused(net->describe(/*training=*/false));
  EXPECT_LT(largest_difference(fused.run(color, info), expected), 1e-4);

  const auto file = fresh_dir("model") / "example.cgsr";
  save_model(file, *net, Provenance{});
  Model loaded = load_model(file);
  EXPECT_EQ(loaded.network->spec(), net->spec());
  loaded.network->eval();
  EXPECT_TRUE(torch::equal(loaded.network->forward(color, info), expected));
  fs::remove_all(file.parent_path());
}

// Subnets skip the example's blocks by their names (blocks.<i>) and narrow its groups.
TEST(ExtendingBackbone, TheToyIsAnElasticNetworkWhoseSubnetsRun) {
  register_examples();
  torch::manual_seed(6);
  SRNetwork net(example_spec(3));
  ElasticNetwork elastic = make_elastic(*net, elastic_options(1));
  SubnetConfig sub{{0, 2}, {{"features", 8}, {"block0_mid", 4}, {"up", 4}}};
  ASSERT_TRUE(elastic.space.contains(sub));
  const auto color = torch::rand({1, 3, 6, 7});
  torch::NoGradGuard no_grad;
  elastic.network->eval();
  const auto g = subnet_graph(*elastic.network, sub);
  const auto out = graph::run(g, network_inputs(g, color, {}))[0].second;
  SRNetwork small = materialize_subnet(*elastic.network, sub);
  small->eval();
  EXPECT_EQ(small->spec().blocks, 2);
  EXPECT_LT(largest_difference(small->forward(color), out), 1e-5);
}

TEST(ExtendingSceneSource, TheBoxIsBuiltFromItsConfigBlockAndRendersADataSet) {
  register_examples();
  const auto doc = std::make_shared<config::Document>(config::Document::parse(
      "scene: {type: box, size: [5, 3, 6], crate: 1.5}\nbad: {type: box, crate: 5}\nmisspelt: {type: boxx}\n",
      "box.yaml"));
  const auto block = [&](const std::string& key) { return config::Block{doc->root()[key], doc, key}; };
  const SceneBundle bundle = make_scene(block("scene"), 3);
  EXPECT_EQ(bundle.scene.meshes.size(), 2u);
  EXPECT_EQ(bundle.camera.keys.size(), 5u);
  try {
    make_scene(block("bad"), 3);
    ADD_FAILURE() << "a crate of 5 m accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("crate"), std::string::npos) << e.what();
  }
  try {
    make_scene(block("misspelt"), 3);
    ADD_FAILURE() << "an unknown scene source accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'box'"), std::string::npos) << e.what();
  }

  RenderJobOptions job;
  job.frames = 3;
  job.resolutions = {"32x24", "64x48"};
  job.shadow_map_size = 64;
  job.scene = block("scene");
  const auto dir = fresh_dir("box");
  const RenderJobResult rendered = run_render_job(job, 3, dir);
  EXPECT_EQ(rendered.rendered, 3);
  finish_render(dir, rendered.manifest);  // nothing else to write into the data set
  const Dataset data = Dataset::open(dir);
  EXPECT_EQ(data.frames(Split::All).size(), 3u);
  fs::remove_all(dir);
}

namespace {
// Scores a subnet by what it keeps: quality grows with the log of its channels and its blocks,
// latency is its MAC count. Deterministic, as an evaluator must be.
class KeptChannelsEvaluator : public Evaluator {
 public:
  explicit KeptChannelsEvaluator(const ArchSpec& spec) : net_(spec) {}
  SubnetScore evaluate(const SubnetConfig& sub) override {
    SubnetScore score;
    score.macs = complexity(subnet_graph(*net_, sub), 16, 12).macs;
    score.latency_ms = static_cast<double>(score.macs) * 1e-6;
    int64_t channels = 0;
    for (const auto& [group, width] : sub.widths) channels += width;
    score.psnr = 20 + std::log(static_cast<double>(channels)) + 0.1 * static_cast<double>(sub.blocks.size());
    return score;
  }

 private:
  SRNetwork net_;
};

SearchOptions search_options(const std::string& yaml) {
  return config::parse_document(config::Document::parse(yaml, "search.yaml"), search_schema());
}
}  // namespace

TEST(ExtendingStrategy, HillClimbingIsNamedInASearchConfigAndSearches) {
  register_examples();
  const SearchOptions options = search_options("strategy: hill_climb\npopulation: 4\ngenerations: 3\n");
  EXPECT_EQ(options.strategy.type, "hill_climb");
  EXPECT_EQ(config::Codec<StrategyOptions>::encode(options.strategy)["type"].as<std::string>(), "hill_climb");
  try {
    search_options("strategy: {type: hill_climb, rate: 0.5}\n");
    ADD_FAILURE() << "an option of a strategy without options accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("has no options"), std::string::npos) << e.what();
  }

  const ArchSpec spec = example_spec(4);
  const ElasticSpace space(spec, elastic_options(2));
  KeptChannelsEvaluator evaluator(spec);
  const auto dir = fresh_dir("search");
  SearchHistory history(dir / "history.jsonl", /*resume=*/false);
  const SearchResult result = run_search(space, evaluator, history, options, "hill_climb");
  EXPECT_EQ(result.generations_run, 3);
  EXPECT_FALSE(result.front.empty());
  std::set<std::string> keys;
  for (const auto& c : result.evaluated) {
    EXPECT_TRUE(space.contains(c.subnet)) << c.key;
    EXPECT_TRUE(keys.insert(c.key).second) << c.key << " evaluated twice";
  }
  fs::remove_all(dir);
}

TEST(ExtendingImportance, TheActivationCriterionOrdersAnElasticNetwork) {
  torch::manual_seed(7);
  SRNetwork net(spec_from_yaml("backbone: pan\nscale: 2\nblocks: 2\n", "pan.yaml"));
  net->eval();
  const auto frames = torch::rand({2, 3, 12, 16});
  const FrameImportance scores = activation_importance(*net, frames, {});
  const FrameImportance magnitude = channel_importance(*net);
  ASSERT_EQ(scores.size(), magnitude.size());
  for (const auto& [group, s] : magnitude) EXPECT_EQ(scores.at(group).sizes(), s.sizes()) << group;

  ElasticNetwork elastic = make_elastic(*net, elastic_options(1), scores);
  elastic.network->eval();
  torch::NoGradGuard no_grad;
  EXPECT_LT(largest_difference(elastic.network->forward(frames), net->forward(frames)), 1e-5);
  for (const auto& [group, sorted] : activation_importance(*elastic.network, frames, {})) {
    const auto step = sorted.slice(0, 1) - sorted.slice(0, 0, -1);  // must not rise
    EXPECT_LE(step.max().item<double>(), 1e-5 * sorted.max().item<double>()) << group;
  }
}

// docs/extending.md shows code as `<!-- from PATH -->` or `<!-- from PATH, lines A-B -->`
// followed by a fenced block: the block must be that file (or those lines of it), to the letter.
TEST(ExtendingPage, QuotesTheExampleFilesToTheLetter) {
  const fs::path root = CGSR_SOURCE_DIR;
  const auto read_lines = [](const fs::path& path) {
    std::ifstream in(path);
    EXPECT_TRUE(in.good()) << path;
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
  };
  const auto page = read_lines(root / "docs" / "extending.md");
  const std::regex marker(R"(<!-- from ([^ ,]+)(, lines (\d+)-(\d+))? -->)");
  std::set<std::string> quoted;
  for (size_t i = 0; i < page.size(); ++i) {
    std::smatch m;
    if (!std::regex_match(page[i], m, marker)) continue;
    SCOPED_TRACE("docs/extending.md:" + std::to_string(i + 1));
    ASSERT_LT(i + 1, page.size());
    ASSERT_EQ(page[i + 1].rfind("```", 0), 0u) << "a fenced block must follow the marker";
    std::vector<std::string> block;
    size_t j = i + 2;
    for (; j < page.size() && page[j] != "```"; ++j) block.push_back(page[j]);
    ASSERT_LT(j, page.size()) << "the block is not closed";
    auto file = read_lines(root / m[1].str());
    if (m[2].matched) {
      const size_t first = std::stoul(m[3].str()), last = std::stoul(m[4].str());
      ASSERT_TRUE(first >= 1 && first <= last && last <= file.size()) << m[0];
      file.erase(file.begin() + static_cast<long>(last), file.end());
      file.erase(file.begin(), file.begin() + static_cast<long>(first - 1));
    }
    EXPECT_EQ(block, file) << m[0] << " does not quote the file as it is";
    quoted.insert(m[1].str());
  }
  for (const char* example : {"tests/extending/example_backbone.cpp", "tests/extending/example_scene_source.cpp",
                              "tests/extending/example_strategy.cpp", "tests/extending/example_importance.cpp"})
    EXPECT_TRUE(quoted.count(example)) << example << " is not quoted by docs/extending.md";
}

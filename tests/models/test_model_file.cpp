// Model files: round trip of spec, weights and provenance; truncation, corruption and weights
// that do not match the spec are errors naming the file.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"
#include "models/model_file.h"
#include "tests/models/model_cases.h"
#include "tests/support/cli_runner.h"

using namespace cgsr;
using namespace cgsr::test;
namespace fs = std::filesystem;

namespace {
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(ModelFile, EveryBackboneRoundTrips) {
  torch::manual_seed(11);
  const auto dir = scratch_dir("model-file-roundtrip");
  for (const auto& c : all_backbone_cases()) {
    SCOPED_TRACE(case_name(c));
    const ArchSpec spec = with_rit(spec_for(c), "hr_pooled", "add", /*geometry=*/true);
    SRNetwork net(spec);
    {
      torch::NoGradGuard no_grad;
      for (auto& p : net->parameters()) p.normal_(0, 0.05);
    }
    Provenance prov;
    prov.stage = "cg-enhanced";
    prov.parent = "runs/train/backbone.cgsr";
    prov.metrics = {{"psnr", 36.16}, {"ssim", 0.9437}};
    prov.config = {{"train", {{"steps", 1000}}}};
    const auto path = dir / (c.backbone + std::to_string(c.scale) + c.colors + ".cgsr");
    save_model(path, *net, prov);
    EXPECT_TRUE(is_model_file(path));
    Model loaded = load_model(path);
    EXPECT_EQ(loaded.network->spec(), spec);
    EXPECT_EQ(loaded.provenance.stage, "cg-enhanced");
    EXPECT_EQ(loaded.provenance.parent, prov.parent);
    EXPECT_DOUBLE_EQ(loaded.provenance.metrics["psnr"].get<double>(), 36.16);
    EXPECT_EQ(loaded.provenance.config["train"]["steps"].get<int>(), 1000);
    const auto [color, info] = random_inputs(spec, 4, 3);
    torch::NoGradGuard no_grad;
    const auto a = net->forward_train(color, info), b = loaded.network->forward_train(color, info);
    EXPECT_TRUE(torch::equal(a.image, b.image));
    EXPECT_TRUE(torch::equal(a.geometry, b.geometry));
  }
  fs::remove_all(dir);
}

TEST(ModelFile, SavingTwiceGivesTheSameBytes) {
  const auto dir = scratch_dir("model-file-bytes");
  SRNetwork net(default_spec("srcnn", 2));
  save_model(dir / "a.cgsr", *net);
  save_model(dir / "b.cgsr", *net);
  EXPECT_EQ(read_file(dir / "a.cgsr"), read_file(dir / "b.cgsr"));
  fs::remove_all(dir);
}

TEST(ModelFile, TruncatedFileIsAnErrorNamingIt) {
  const auto dir = scratch_dir("model-file-truncated");
  SRNetwork net(default_spec("pan", 2));
  const auto path = dir / "pan.cgsr";
  save_model(path, *net);
  const std::string bytes = read_file(path);
  for (size_t keep : {bytes.size() - 1, bytes.size() / 2, size_t{40}, size_t{20}}) {
    SCOPED_TRACE(keep);
    write_file_atomic(path, bytes.substr(0, keep));
    const auto what = error_of([&] { load_model(path); });
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    EXPECT_NE(what.find("truncated"), std::string::npos) << what;
  }
  fs::remove_all(dir);
}

TEST(ModelFile, CorruptionAndForeignFilesAreErrors) {
  const auto dir = scratch_dir("model-file-corrupt");
  SRNetwork net(default_spec("srcnn", 3));
  const auto path = dir / "srcnn.cgsr";
  save_model(path, *net);
  std::string bytes = read_file(path);
  bytes[bytes.size() / 2] ^= 0x5a;
  write_file_atomic(path, bytes);
  EXPECT_NE(error_of([&] { load_model(path); }).find("checksum"), std::string::npos);
  write_file_atomic(path, "backbone: pan\n");
  EXPECT_NE(error_of([&] { load_model(path); }).find("not a cgsr model file"), std::string::npos);
  EXPECT_FALSE(is_model_file(path));
  EXPECT_NE(error_of([&] { load_model(dir / "missing.cgsr"); }).find("no such model file"), std::string::npos);
  fs::remove_all(dir);
}

TEST(ModelFile, WeightsThatDoNotMatchTheSpecAreErrors) {
  const auto dir = scratch_dir("model-file-mismatch");
  SRNetwork net(default_spec("pan", 2));
  ModelFileContents contents;
  for (const auto& p : net->named_parameters()) contents.tensors.emplace_back(p.key(), p.value());
  // A spec with a narrower layer group than the stored weights.
  contents.spec = default_spec("pan", 2);
  contents.spec.widths.set("block2_att", 10);
  write_model_file(dir / "narrow.cgsr", contents);
  const auto what = error_of([&] { load_model(dir / "narrow.cgsr"); });
  EXPECT_NE(what.find((dir / "narrow.cgsr").string()), std::string::npos) << what;
  EXPECT_NE(what.find("backbone.blocks.2.pa_conv.k2.weight"), std::string::npos) << what;
  // A missing tensor.
  contents.spec = default_spec("pan", 2);
  contents.tensors.pop_back();
  write_model_file(dir / "missing.cgsr", contents);
  EXPECT_NE(error_of([&] { load_model(dir / "missing.cgsr"); }).find("missing tensor backbone.conv_last.bias"),
            std::string::npos);
  // Non-finite weights.
  SRNetwork broken(default_spec("srcnn", 2));
  {
    torch::NoGradGuard no_grad;
    broken->named_parameters()["backbone.conv2.weight"][0][0][0][0] = std::nanf("");
  }
  save_model(dir / "nan.cgsr", *broken);
  EXPECT_NE(error_of([&] { load_model(dir / "nan.cgsr"); }).find("NaN"), std::string::npos);
  fs::remove_all(dir);
}

TEST(ModelFile, ExpectedRenderingChannelsAreRecorded) {
  const auto dir = scratch_dir("model-file-channels");
  ArchSpec s = default_spec("edsr", 2);
  s.rit.enabled = true;
  s.rit.channels = {"normal", "depth"};
  SRNetwork net(s);
  save_model(dir / "edsr.cgsr", *net);
  const auto contents = read_model_file(dir / "edsr.cgsr");
  EXPECT_EQ(contents.spec.rit.channels, (std::vector<std::string>{"depth", "normal"}));
  EXPECT_EQ(load_model(dir / "edsr.cgsr").network->input_channels(),
            (std::vector<RenderChannel>{RenderChannel::Depth, RenderChannel::Normal}));
  fs::remove_all(dir);
}

namespace {
// The file a cgsr from before `rit.depth_encoding` wrote: the same bytes with that spec line
// removed, lengths and checksum redone (model_file.h layout).
void drop_depth_encoding(const fs::path& path) {
  const std::string bytes = read_file(path);
  const auto u64 = [&](size_t at) {
    uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(bytes[at + i]);
    return v;
  };
  const uint64_t meta_size = u64(12), weight_size = u64(20);
  auto meta = nlohmann::ordered_json::parse(bytes.substr(28, meta_size));
  std::string spec = meta["spec"];
  const auto line = spec.find("  depth_encoding: log\n");
  ASSERT_NE(line, std::string::npos) << spec;
  spec.erase(line, std::string("  depth_encoding: log\n").size());
  meta["spec"] = spec;
  const std::string new_meta = meta.dump();
  std::string out = bytes.substr(0, 12);
  const auto put = [&](uint64_t v) {
    for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  };
  put(new_meta.size());
  put(weight_size);
  out += new_meta + bytes.substr(28 + meta_size, weight_size);
  uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : out) h = (h ^ c) * 1099511628211ULL;
  put(h);
  write_file_atomic(path, out);
}
}  // namespace

TEST(ModelFile, FilesFromBeforeDepthEncodingsReadZBufferDepth) {
  const auto dir = scratch_dir("model-file-legacy");
  SRNetwork net = build_network(with_rit(default_spec("pan", 2)), 11);
  EXPECT_EQ(net->spec().rit.depth_encoding, "log");  // what new networks read
  save_model(dir / "old.cgsr", *net);
  drop_depth_encoding(dir / "old.cgsr");
  Model old = load_model(dir / "old.cgsr");
  EXPECT_EQ(old.network->spec().rit.depth_encoding, "zbuffer");
  EXPECT_EQ(old.network->depth_encoding(), DepthEncoding::ZBuffer);
  // Same weights, same function: only the input contract differs.
  const auto [color, info] = random_inputs(net->spec(), 6, 5);
  torch::NoGradGuard no_grad;
  old.network->eval();
  EXPECT_TRUE(torch::equal(old.network->forward(color, info), net->forward(color, info)));
  fs::remove_all(dir);
}

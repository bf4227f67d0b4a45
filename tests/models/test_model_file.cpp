// Model files: round trip of spec, weights and provenance; truncation, corruption and weights
// that do not match the spec are errors naming the file.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <functional>
#include <regex>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/hash.h"
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
    const ArchSpec spec = with_rit(spec_for(c), "hr_pooled", "add", has_hr_features(c.backbone));
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
    if (has_hr_features(c.backbone)) {
      EXPECT_TRUE(torch::equal(a.geometry, b.geometry));
    }
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
uint64_t u64_at(const std::string& bytes, size_t at) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(bytes[at + i]);
  return v;
}

void put_u64(std::string& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

// A model file of `version` with these sections, lengths and checksum as the header says
// (model_file.h layout).
std::string assemble(uint32_t version, const std::string& meta, const std::string& weights) {
  std::string out = "CGSRMODL";
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((version >> (8 * i)) & 0xff));
  put_u64(out, meta.size());
  put_u64(out, weights.size());
  out += meta + weights;
  put_u64(out, model_file_checksum(out));
  return out;
}

// Rewrites the model file at `path` through `edit` of its metadata and weights, keeping its version.
void rewrite(const fs::path& path, const std::function<void(nlohmann::ordered_json&, std::string&)>& edit) {
  const std::string bytes = read_file(path);
  const uint64_t meta_size = u64_at(bytes, 12), weight_size = u64_at(bytes, 20);
  auto meta = nlohmann::ordered_json::parse(bytes.substr(28, meta_size));
  std::string weights = bytes.substr(28 + meta_size, weight_size);
  edit(meta, weights);
  const uint32_t version = static_cast<unsigned char>(bytes[8]);
  write_file_atomic(path, assemble(version, meta.dump(), weights));
}

// The file a cgsr from before `rit.depth_encoding` wrote: the same bytes with that spec line removed.
void drop_depth_encoding(const fs::path& path) {
  rewrite(path, [](nlohmann::ordered_json& meta, std::string&) {
    std::string spec = meta["spec"];
    const auto line = spec.find("  depth_encoding: log\n");
    ASSERT_NE(line, std::string::npos) << spec;
    spec.erase(line, std::string("  depth_encoding: log\n").size());
    meta["spec"] = spec;
  });
}

const fs::path kVersion1File = fs::path(CGSR_SOURCE_DIR) / "tests/data/model_file_v1.cgsr";
}  // namespace

TEST(ModelFile, FilesFromBeforeDepthEncodingsReadZBufferDepth) {
  const auto dir = scratch_dir("model-file-legacy");
  SRNetwork net = build_network(with_rit(default_spec("pan", 2)), 11);
  EXPECT_EQ(net->spec().rit.depth_encoding, DepthEncoding::Log);  // what new networks read
  save_model(dir / "old.cgsr", *net);
  drop_depth_encoding(dir / "old.cgsr");
  Model old = load_model(dir / "old.cgsr");
  EXPECT_EQ(old.network->spec().rit.depth_encoding, DepthEncoding::ZBuffer);
  EXPECT_EQ(old.network->depth_encoding(), DepthEncoding::ZBuffer);
  // Same weights, same function: only the input contract differs.
  const auto [color, info] = random_inputs(net->spec(), 6, 5);
  torch::NoGradGuard no_grad;
  old.network->eval();
  EXPECT_TRUE(torch::equal(old.network->forward(color, info), net->forward(color, info)));
  fs::remove_all(dir);
}

TEST(ModelFile, Version2IsRawFloat32WithTheFnv1aChecksum) {
  const auto dir = scratch_dir("model-file-v2");
  SRNetwork net = build_network(default_spec("srcnn", 2), 5);
  save_model(dir / "srcnn.cgsr", *net);
  const std::string bytes = read_file(dir / "srcnn.cgsr");
  EXPECT_EQ(static_cast<unsigned char>(bytes[8]), 2);
  const uint64_t meta_size = u64_at(bytes, 12), weight_size = u64_at(bytes, 20);
  // The checksum is plain FNV-1a 64 (the published basis) of everything before it.
  EXPECT_EQ(u64_at(bytes, bytes.size() - 8), fnv1a64(std::string_view(bytes).substr(0, bytes.size() - 8)));
  const auto meta = nlohmann::ordered_json::parse(bytes.substr(28, meta_size));
  // Weights: each parameter's float32 values, in the metadata's order, back to back.
  size_t at = 28 + meta_size;
  const auto params = net->named_parameters();
  ASSERT_EQ(meta["tensors"].size(), params.size());
  for (const auto& t : meta["tensors"]) {
    SCOPED_TRACE(t.dump());
    EXPECT_EQ(t["dtype"], "float32");
    const torch::Tensor p = params[t["name"].get<std::string>()].contiguous();
    EXPECT_EQ(t["shape"].get<std::vector<int64_t>>(), p.sizes().vec());
    const size_t n = p.numel() * sizeof(float);
    EXPECT_EQ(std::memcmp(bytes.data() + at, p.data_ptr<float>(), n), 0);
    at += n;
  }
  EXPECT_EQ(at, 28 + meta_size + weight_size);
  fs::remove_all(dir);
}

TEST(ModelFile, Version1FilesStillLoadWithTheSameWeights) {
  // tests/data/model_file_v1.cgsr was written by the version 1 writer (a torch::save archive,
  // checksummed with the short basis). LibTorch's own reader of that archive is the reference.
  const std::string bytes = read_file(kVersion1File);
  ASSERT_EQ(static_cast<unsigned char>(bytes[8]), 1);
  EXPECT_EQ(u64_at(bytes, bytes.size() - 8),
            fnv1a64(std::string_view(bytes).substr(0, bytes.size() - 8), kLegacyFnv1a64Basis));
  const uint64_t meta_size = u64_at(bytes, 12), weight_size = u64_at(bytes, 20);
  std::vector<torch::Tensor> reference;
  std::istringstream archive(bytes.substr(28 + meta_size, weight_size));
  torch::load(reference, archive);

  const ModelFileContents contents = read_model_file(kVersion1File);
  ASSERT_EQ(contents.tensors.size(), reference.size());
  ASSERT_EQ(contents.tensors.size(), 25u);
  for (size_t i = 0; i < reference.size(); ++i) {
    SCOPED_TRACE(contents.tensors[i].first);
    EXPECT_TRUE(torch::equal(contents.tensors[i].second, reference[i]));
  }
  EXPECT_EQ(contents.tensors.front().first, "backbone.conv_first.weight");
  EXPECT_EQ(contents.provenance.stage, "cg-enhanced");
  EXPECT_EQ(spec_summary(contents.spec), "pan x2 + rit[depth+normal+normal_angle+edge, w2, lr, concat, log depth]");

  // It runs, and saving it again writes version 2 with the same weights.
  const auto dir = scratch_dir("model-file-v1");
  Model old = load_model(kVersion1File);
  save_model(dir / "v2.cgsr", *old.network, old.provenance);
  EXPECT_EQ(static_cast<unsigned char>(read_file(dir / "v2.cgsr")[8]), 2);
  const ModelFileContents again = read_model_file(dir / "v2.cgsr");
  ASSERT_EQ(again.tensors.size(), reference.size());
  for (size_t i = 0; i < reference.size(); ++i) EXPECT_TRUE(torch::equal(again.tensors[i].second, reference[i]));
  fs::remove_all(dir);
}

TEST(ModelFile, Version1ArchivesAreCheckedBeforeAllocating) {
  const auto dir = scratch_dir("model-file-v1-bad");
  const auto path = dir / "v1.cgsr";
  const auto error_after = [&](const std::function<void(nlohmann::ordered_json&, std::string&)>& edit) {
    fs::copy_file(kVersion1File, path, fs::copy_options::overwrite_existing);
    rewrite(path, edit);
    const auto what = error_of([&] { load_model(path); });
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    return what;
  };
  // A shape that does not match its record's size.
  auto what = error_after([](auto& meta, auto&) { meta["tensors"][0]["shape"] = {4, 3, 3, 4}; });
  EXPECT_NE(what.find("record data/0 holds 432 bytes, tensor backbone.conv_first.weight of shape [4, 3, 3, 4] needs 576"),
            std::string::npos)
      << what;
  // A shape larger than the whole archive.
  what = error_after([](auto& meta, auto&) { meta["tensors"][3]["shape"] = {1 << 20, 1 << 20}; });
  EXPECT_NE(what.find("tensor backbone.blocks.0.conv1_b.weight: shape [1048576, 1048576] needs more than"),
            std::string::npos)
      << what;
  // A record whose directory entry claims 4 GB: what made torch::load allocate before it failed.
  what = error_after([](auto&, std::string& zip) {
    const size_t entry = zip.find(std::string("PK\x01\x02", 4));
    ASSERT_NE(entry, std::string::npos);
    for (size_t i : {20, 24}) zip.replace(entry + i, 4, "\xff\xff\xff\xfe");
  });
  EXPECT_NE(what.find("record archive/data/0 runs past the archive"), std::string::npos) << what;
  // A tensor whose record is missing.
  what = error_after([](auto& meta, auto&) { meta["tensors"].push_back({{"name", "extra.x"}, {"shape", {0}}}); });
  EXPECT_NE(what.find("25 tensor records for the 26 tensors the metadata lists"), std::string::npos) << what;
  fs::remove_all(dir);
}

TEST(ModelFile, DeclaredShapesAreCheckedBeforeAllocating) {
  const auto dir = scratch_dir("model-file-bounds");
  SRNetwork net = build_network(default_spec("srcnn", 2), 3);
  const auto path = dir / "srcnn.cgsr";
  const auto error_after = [&](const std::function<void(nlohmann::ordered_json&, std::string&)>& edit) {
    save_model(path, *net);
    rewrite(path, edit);
    const auto what = error_of([&] { load_model(path); });
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    return what;
  };
  const auto contains = [](const std::string& what, const std::string& part) {
    return what.find(part) != std::string::npos;
  };
  // Larger than the bytes left, with a product that overflows int64, negative, too many dimensions.
  auto what = error_after([](auto& meta, auto&) { meta["tensors"][1]["shape"] = {int64_t{1} << 40}; });
  EXPECT_TRUE(contains(what, "tensor backbone.conv1.bias: shape [1099511627776] needs more than")) << what;
  what = error_after([](auto& meta, auto&) { meta["tensors"][0]["shape"] = {1 << 30, 1 << 30, 1 << 30, 1 << 30}; });
  EXPECT_TRUE(contains(what, "tensor backbone.conv1.weight: shape [1073741824, 1073741824, 1073741824, 1073741824] "
                             "needs more than")) << what;
  what = error_after([](auto& meta, auto&) { meta["tensors"][0]["shape"] = {-64, 3, 9, 9}; });
  EXPECT_TRUE(contains(what, "tensor backbone.conv1.weight: shape [-64,3,9,9] holds something other than a size >= 0"))
      << what;
  what = error_after([](auto& meta, auto&) { meta["tensors"][0]["shape"] = {1, 1, 1, 1, 1, 1, 1, 1, 1}; });
  EXPECT_TRUE(contains(what, "tensor backbone.conv1.weight: shape must be a list of at most 8 sizes")) << what;
  what = error_after([](auto& meta, auto&) { meta["tensors"][2]["dtype"] = "float64"; });
  EXPECT_TRUE(contains(what, "tensor backbone.conv2.weight: dtype \"float64\", expected \"float32\"")) << what;
  // Bytes the tensors do not account for, and a list longer than the limit.
  what = error_after([](auto&, std::string& weights) { weights += "1234"; });
  EXPECT_TRUE(contains(what, "the weights hold " + std::to_string(u64_at(read_file(path), 20)) + " bytes, the tensors "
                             "the metadata lists " + std::to_string(u64_at(read_file(path), 20) - 4))) << what;
  what = error_after([](auto& meta, auto&) {
    for (size_t i = 0; i <= kMaxModelTensors; ++i)
      meta["tensors"].push_back({{"name", "extra." + std::to_string(i)}, {"dtype", "float32"}, {"shape", {0}}});
  });
  EXPECT_TRUE(contains(what, "more than the limit of 65536")) << what;
  // Section lengths beyond the caps are refused from the header alone.
  write_file_atomic(path, assemble(2, "{}", ""));
  std::string bytes = read_file(path);
  for (int i = 0; i < 8; ++i) bytes[20 + i] = i == 4 ? 1 : 0;  // weights length 2^32
  write_file_atomic(path, bytes.substr(0, bytes.size() - 8) + std::string(8, '\0'));
  what = error_of([&] { load_model(path); });
  EXPECT_TRUE(contains(what, "4294967296 bytes of weights, more than the limit of 2147483648")) << what;
  fs::remove_all(dir);
}

TEST(ModelFile, ASpecFarLargerThanItsWeightsIsRefusedBeforeBuilding) {
  const auto dir = scratch_dir("model-file-budget");
  const auto path = dir / "pan.cgsr";
  SRNetwork net(default_spec("pan", 2));
  save_model(path, *net);
  // 200000 features would be hundreds of GB of parameters; the file stores a few thousand values.
  rewrite(path, [](nlohmann::ordered_json& meta, std::string&) {
    const std::string spec = meta["spec"];
    ASSERT_NE(spec.find("  features: "), std::string::npos) << spec;
    meta["spec"] = std::regex_replace(spec, std::regex("  features: \\d+"), "  features: 200000");
  });
  const auto what = error_of([&] { load_model(path); });
  EXPECT_NE(what.find(path.string() + ": the spec describes a network of more than"), std::string::npos) << what;
  fs::remove_all(dir);
}

// The provenance object of a model file's metadata: its keys in order, and missing keys (older
// files) read as their defaults.
TEST(ModelFile, ProvenanceJsonKeepsItsKeysAndReadsMissingOnesAsDefaults) {
  Provenance p;
  p.stage = "pruned";
  p.parent = "search/model.cgsr";
  p.metrics = {{"psnr", 30.5}};
  EXPECT_EQ(nlohmann::ordered_json(p).dump(),
            R"({"stage":"pruned","parent":"search/model.cgsr","config":{},"metrics":{"psnr":30.5},"extra":{}})");
  const Provenance back = provenance_from_json(nlohmann::ordered_json(p), "m.cgsr");
  EXPECT_EQ(back.stage, p.stage);
  EXPECT_EQ(back.metrics, p.metrics);
  const Provenance old = provenance_from_json(nlohmann::ordered_json::parse(R"({"stage":"backbone"})"), "m.cgsr");
  EXPECT_EQ(old.stage, "backbone");
  EXPECT_EQ(old.parent, "");
  EXPECT_TRUE(old.config.is_object() && old.config.empty());
  EXPECT_THROW(provenance_from_json(nlohmann::ordered_json::parse(R"({"stage":3})"), "m.cgsr"), Error);
  EXPECT_THROW(provenance_from_json(nlohmann::ordered_json::array(), "m.cgsr"), Error);
}

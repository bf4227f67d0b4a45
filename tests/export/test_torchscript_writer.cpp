// The TorchScript writer: registered parameters and buffers, a generated forward that computes
// what our forward computes, files that load back, and clear errors.

#include <gtest/gtest.h>

#include <torch/script.h>
#include <torch/torch.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "export/exporter.h"
#include "export/torchscript_runner.h"
#include "export/torchscript_writer.h"
#include "models/inference.h"
#include "tests/export/export_cases.h"
#include "tests/support/cli_runner.h"

namespace cgsr {
namespace {

TEST(TorchScriptWriter, ModuleHoldsTheGraphTensorsAndComputesOurForward) {
  SRNetwork net = test::build_network(test::with_rit(default_spec("edsr", 2), "hr_pooled", "concat"), 1);
  const graph::Graph g = net->describe();
  torch::jit::Module m = torchscript_module(g);
  std::map<std::string, torch::Tensor> params, buffers;
  for (const auto& p : m.named_parameters(/*recurse=*/false)) params[p.name] = p.value;
  for (const auto& b : m.named_buffers(/*recurse=*/false)) buffers[b.name] = b.value;
  // Trainable tensors are parameters under their module path, constants are buffers.
  ASSERT_TRUE(params.count("backbone__head__weight"));
  EXPECT_TRUE(torch::equal(params["backbone__head__weight"], net->backbone().named_parameters()["head.weight"]));
  EXPECT_TRUE(params.count("rit__gate__scale"));
  // EDSR's mean shift is a fixed 1x1 conv in the graph: constants, so buffers.
  EXPECT_TRUE(buffers.count("backbone__sub_mean__weight"));
  EXPECT_TRUE(buffers.count("backbone__sub_mean__bias"));
  EXPECT_FALSE(params.count("backbone__sub_mean__bias"));
  EXPECT_EQ(static_cast<int64_t>(params.size()), static_cast<int64_t>(net->named_parameters().size()));

  const std::string source = torchscript_source(g);
  EXPECT_NE(source.find("def forward(self, lr_color: Tensor, hr_render_info: Tensor) -> Tensor:"), std::string::npos);
  EXPECT_NE(source.find("torch.pixel_shuffle("), std::string::npos);
  EXPECT_NE(source.find("torch.avg_pool2d("), std::string::npos);

  torch::manual_seed(2);
  const auto color = torch::rand({2, 3, 7, 9});
  const auto info = torch::rand({2, net->spec().rit.info_width(), 14, 18});
  torch::NoGradGuard no_grad;
  const auto got = m.forward({color, info}).toTensor();
  EXPECT_TRUE(torch::equal(got, infer(*net, color, info, MemoryLayout::Nchw)));  // the same kernels, bit for bit
}

TEST(TorchScriptWriter, SavedFilesLoadBackWithTheirMetadata) {
  const auto dir = test::scratch_dir("torchscript-writer");
  SRNetwork net = test::build_network(test::spec_for({"srcnn", 4, "y"}), 3);
  ExportOptions o;
  o.format = ExportFormat::TorchScript;
  const auto exported = export_network(*net, dir / "srcnn.pt", o);
  EXPECT_TRUE(exported.dynamic_size);
  torch::jit::ExtraFilesMap extra{{"cgsr.spec", ""}, {"cgsr.scale", ""}};
  torch::jit::load(exported.file.string(), torch::kCPU, extra);
  EXPECT_EQ(extra["cgsr.scale"], "4");
  EXPECT_EQ(spec_from_yaml(extra["cgsr.spec"], "extra file"), net->spec());
  const auto color = torch::rand({1, 3, 5, 6});
  const auto out = run_torchscript_libtorch(exported.file, {{"lr_color", color}});
  EXPECT_TRUE(torch::equal(out, infer(*net, color)));
  // Inputs are matched by name: a wrong or missing one is a clear error.
  EXPECT_THROW(run_torchscript_libtorch(exported.file, {{"color", color}}), Error);
  EXPECT_THROW(run_torchscript_libtorch(exported.file, {{"lr_color", color}, {"hr_render_info", color}}), Error);
  std::filesystem::remove_all(dir);
}

TEST(TorchScriptWriter, CorruptFilesAndUnknownOpsAreClearErrors) {
  const auto dir = test::scratch_dir("torchscript-corrupt");
  write_file_atomic(dir / "bad.pt", "not a zip archive");
  try {
    load_torchscript(dir / "bad.pt");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.context(), (dir / "bad.pt").string());
  }
  EXPECT_THROW(load_torchscript(dir / "missing.pt"), Error);
  SRNetwork net = test::build_network(test::shrunk_pan(2), 4);
  graph::Graph g = net->describe();
  g.ops[3].kind = static_cast<graph::OpKind>(42);
  try {
    torchscript_module(g);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(g.ops[3].name), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace cgsr

#include "export/hybrid_verification.h"

#include <torch/torch.h>

#include <ATen/CPUGeneratorImpl.h>

#include <algorithm>

#include "core/error.h"
#include "export/onnxruntime_runner.h"
#include "export/selector_onnx.h"
#include "pruning/pattern_networks.h"

namespace cgsr {

namespace {

struct SelectorFrame {
  std::string label;
  torch::Tensor info, previous;  // previous undefined: a first frame
};

// Three frames in a row: a first frame, one with a previous frame, and one whose motion leaves
// the frame (some pixels move a thousand frame widths) so the clamp matters.
std::vector<SelectorFrame> selector_frames(const std::vector<RenderChannel>& channels, int64_t w, int64_t h,
                                           uint64_t seed) {
  auto generator = at::detail::createCPUGenerator(seed);
  const auto names = channel_names(channels);
  const auto f0 = random_render_info(names, 1, h, w, generator);
  const auto f1 = random_render_info(names, 1, h, w, generator);
  auto f2 = random_render_info(names, 1, h, w, generator);
  bool has_motion = false;
  int64_t at = 0;
  for (auto ch : channels) {
    if (ch == RenderChannel::Motion) {
      has_motion = true;
      auto motion = f2.slice(1, at, at + 2);
      const auto wild = torch::rand(motion.sizes(), generator) < 0.2;
      const auto sign = torch::rand(motion.sizes(), generator).gt(0.5).to(torch::kFloat) * 2 - 1;
      motion.copy_(torch::where(wild, sign * 1000.0 * static_cast<double>(std::max(w, h)), motion));
    }
    at += channel_width(ch);
  }
  return {{"first frame", f0, {}},
          {"next frame", f1, f0},
          {has_motion ? "motion off-frame" : "third frame", f2, f1}};
}

}  // namespace

VerifyReport verify_hybrid_export(const HybridModel& model, const HybridExport& exported, const VerifyOptions& options,
                                  uint64_t seed) {
  CGSR_CHECK(!exported.patterns.empty(), "verify_hybrid_export: nothing was exported");
  const int64_t w = exported.patterns.front().width, h = exported.patterns.front().height;
  torch::NoGradGuard no_grad;

  // Each pattern file against cgsr's own run of that pattern, in every runtime of its format.
  PatternNetworks patterns(*model.network, model.pool);
  CGSR_CHECK(patterns.size() == static_cast<int>(exported.patterns.size()),
             "verify_hybrid_export: the export holds " + std::to_string(exported.patterns.size()) +
                 " patterns, the model " + std::to_string(patterns.size()));
  std::vector<VerifyCase> cases;
  for (int k = 0; k < patterns.size(); ++k) {
    const ExportedModel& e = exported.patterns[k];
    VerifyCase c;
    c.label = "pattern " + std::to_string(k);
    c.file = e.file;
    c.format = e.format;
    const NamedTensors inputs = random_inputs(e.signature, w, h, seed + static_cast<uint64_t>(k));
    c.inputs.push_back(inputs);
    c.expected.push_back(patterns.run(k, find_tensor(inputs, kExportColorInput), info_tensor(e.signature, inputs)));
    cases.push_back(std::move(c));
  }
  // Named runtimes apply to the files that runtime reads: the patterns' format here, the
  // selector (ONNX) below.
  VerifyOptions pattern_options = options;
  if (!options.runtimes.empty()) {
    const auto readers = runtimes_for(exported.patterns.front().format);
    pattern_options.runtimes.clear();
    for (Runtime r : options.runtimes)
      if (std::find(readers.begin(), readers.end(), r) != readers.end()) pattern_options.runtimes.push_back(r);
    if (pattern_options.runtimes.empty())
      throw Error(exported.dir.string(), std::string("none of the requested runtimes reads ") +
                                             enum_name(exported.patterns.front().format) + " pattern files");
  }
  VerifyReport report = verify_exports(cases, pattern_options);

  // The selector in ONNX Runtime against DynamicSamplers on the same frames.
  DynamicSamplers sampler = model.samplers;  // forward() is not const
  sampler->eval();
  const auto channels = sampler->options().render_channels();
  const auto frames = selector_frames(channels, w, h, seed + 7919);
  std::vector<torch::Tensor> expected;
  for (const auto& f : frames)
    expected.push_back(sampler->forward(sampler_input(f.info, f.previous, channels, sampler->options().grid))
                           .reshape({1, -1}));

  std::string skipped;
  const bool explicit_runtimes = !options.runtimes.empty();
  if (explicit_runtimes &&
      std::find(options.runtimes.begin(), options.runtimes.end(), Runtime::OnnxRuntime) == options.runtimes.end())
    skipped = "the selector runs in onnxruntime, which was not requested";
  else
    skipped = OnnxRuntimeRunner::unavailable_reason();
  if (!skipped.empty() && explicit_runtimes &&
      std::find(options.runtimes.begin(), options.runtimes.end(), Runtime::OnnxRuntime) != options.runtimes.end())
    throw Error(exported.selector_file.string(), "cannot verify in onnxruntime: " + skipped);

  const size_t first = report.checks.size();
  OrtModelJob job;
  job.model = exported.selector_file;
  for (const auto& f : frames) {
    RuntimeCheck check;
    check.label = "selector";
    check.file = exported.selector_file;
    check.runtime = Runtime::OnnxRuntime;
    check.input = f.label;
    check.skipped = skipped;
    report.checks.push_back(check);
    // A first frame passes its own information as the previous one (the change is then zero).
    job.runs.push_back({{{kSelectorInfoInput, f.info}, {kSelectorPreviousInput, f.previous.defined() ? f.previous : f.info}},
                        0, 1});
  }
  if (!skipped.empty()) return report;

  const auto result = OnnxRuntimeRunner(options.threads).run({job}).front();
  for (size_t i = 0; i < frames.size(); ++i) {
    RuntimeCheck& check = report.checks[first + i];
    if (!result.error.empty()) {
      check.error = result.error;
      continue;
    }
    const auto& outputs = result.runs.at(i).outputs;
    const torch::Tensor scores = find_tensor(outputs, kSelectorScores), pattern = find_tensor(outputs, kSelectorPattern);
    if (!scores.defined() || !pattern.defined() || pattern.numel() != 1) {
      check.error = "the selector did not produce 'scores' and a single 'pattern'";
      continue;
    }
    check.ran = true;
    check.max_abs_error = max_abs_error(scores, expected[i]);
    const int64_t ours = expected[i].argmax(1).item<int64_t>(), theirs = pattern.item<int64_t>();
    check.passed = check.max_abs_error <= options.tolerance && ours == theirs;
    if (scores.sizes() != expected[i].sizes())
      check.error = "scores " + std::to_string(scores.numel()) + " values, ours " + std::to_string(expected[i].numel());
    else if (ours != theirs)
      check.error = "chose pattern " + std::to_string(theirs) + ", cgsr chose " + std::to_string(ours);
  }
  return report;
}

}  // namespace cgsr

#include "export/hybrid_export.h"

#include <torch/torch.h>

#include <system_error>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/text.h"
#include "export/selector_onnx.h"
#include "models/arch_spec.h"
#include "pruning/pattern_networks.h"

namespace cgsr {

namespace {

nlohmann::ordered_json dims_json(std::initializer_list<int64_t> dims) {
  return nlohmann::ordered_json(std::vector<int64_t>(dims));
}

// Where each channel sits in a rendering-information tensor: rows [first_row, first_row + width).
nlohmann::ordered_json channel_rows_json(const std::vector<RenderChannel>& channels) {
  auto rows = nlohmann::ordered_json::array();
  int64_t row = 0;
  for (auto ch : channels) {
    rows.push_back({{"name", channel_name(ch)}, {"first_row", row}, {"rows", channel_width(ch)}});
    row += channel_width(ch);
  }
  return rows;
}

nlohmann::ordered_json network_inputs_json(const ExportSignature& signature, const SRNetworkImpl& net, int64_t w,
                                      int64_t h) {
  auto inputs = nlohmann::ordered_json::array();
  for (const auto& port : signature.inputs) {
    nlohmann::ordered_json in;
    in["name"] = port.name;
    in["shape"] = dims_json({1, port.channels, h * port.factor, w * port.factor});
    if (port.name == kExportColorInput) {
      in["content"] = "low-resolution RGB, display-referred, in [0,1]";
    } else {
      in["content"] = "rendering information at " +
                      std::string(port.factor == 1 ? "the LR size" : std::to_string(port.factor) + "x the LR size");
      in["channels"] = channel_rows_json(parse_channels(port.channel_names));
      in["depth_encoding"] = enum_name(net.depth_encoding());
    }
    inputs.push_back(in);
  }
  return inputs;
}

}  // namespace

std::string pattern_file_name(int k, ExportFormat format) {
  return "pattern_" + std::to_string(k) + (format == ExportFormat::Onnx ? ".onnx" : ".pt");
}

HybridExport export_hybrid(const HybridModel& model, const std::filesystem::path& dir, const ExportOptions& options) {
  if (!model.network || !model.samplers)
    throw Error("hybrid export", "the model has no network or no dynamic sampler: not a hybrid-pruned model");
  if (options.dynamic_size)
    throw Error("hybrid export", "the selector pools a fixed frame size: export a hybrid model at one --input size");
  if (options.width <= 0 || options.height <= 0)
    throw Error("hybrid export", "needs a positive LR size, got " + std::to_string(options.width) + "x" +
                                     std::to_string(options.height));
  if (model.pool.size() < 1) throw Error("hybrid export", "the pattern pool is empty");
  if (model.samplers->patterns().size() != 1 || model.samplers->patterns().front() != model.pool.size())
    throw Error("hybrid export", "the sampler scores " + std::to_string(model.samplers->patterns().front()) +
                                     " patterns, the pool holds " + std::to_string(model.pool.size()));
  if (dir.empty()) throw Error("hybrid export", "no output directory given");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw Error(dir.string(), "cannot create the output directory: " + (ec ? ec.message() : "not a directory"));

  const SRNetworkImpl& net = *model.network;
  const int64_t w = options.width, h = options.height;
  PatternNetworks patterns(net, model.pool);
  HybridExport out;
  out.dir = dir;

  // The patterns: each its own network file, with the network's metadata and its index.
  auto pattern_entries = nlohmann::ordered_json::array();
  const bool timed = model.latency.median_ms.size() == static_cast<size_t>(model.pool.size());
  for (int k = 0; k < patterns.size(); ++k) {
    auto metadata = export_metadata(net);
    metadata.emplace_back("cgsr.hybrid_pattern", std::to_string(k));
    metadata.emplace_back("cgsr.hybrid_patterns", std::to_string(patterns.size()));
    const std::filesystem::path file = dir / pattern_file_name(k, options.format);
    try {
      out.patterns.push_back(export_graph(patterns.graph(k), file, options, metadata));
    } catch (const Error& e) {
      throw e.within("hybrid export: pattern " + std::to_string(k));
    }
    const Complexity cost = patterns.cost(k, w, h);
    nlohmann::ordered_json p;
    p["index"] = k;
    p["file"] = file.filename().string();
    p["channel_fraction"] = model.pool.channel_fraction(k);
    p["macs"] = cost.macs;
    p["parameters"] = cost.params;
    p["latency_ms"] = timed ? nlohmann::ordered_json(model.latency.median_ms[k]) : nlohmann::ordered_json(nullptr);
    pattern_entries.push_back(p);
  }
  // Every pattern has the same interface (they differ in inner widths only).
  const ExportSignature& signature = out.patterns.front().signature;
  for (const auto& p : out.patterns)
    CGSR_CHECK(p.signature.inputs.size() == signature.inputs.size() && p.signature.scale() == signature.scale(),
               "hybrid export: the patterns' interfaces differ");

  // The selector.
  const DynamicSamplersImpl& sampler = *model.samplers;
  const SamplerOptions& so = sampler.options();
  const auto sampler_channels = so.render_channels();
  const int64_t c = total_width(sampler_channels);
  out.selector_file = dir / kSelectorFile;
  write_file_atomic(out.selector_file,
                    selector_onnx_bytes(sampler, w, h,
                                        {{"cgsr.selector_channels", join(channel_names(sampler_channels))},
                                         {"cgsr.selector_grid", std::to_string(so.grid)},
                                         {"cgsr.hybrid_patterns", std::to_string(patterns.size())}}));
  check_onnx_file(out.selector_file);

  // The manifest: what an engine integrator needs, in words where a number alone would not say.
  nlohmann::ordered_json m;
  m["format"] = "cgsr-hybrid";
  m["format_version"] = kHybridManifestVersion;
  m["model"] = spec_summary(net.spec());
  m["scale"] = signature.scale();
  m["lr_size"] = {{"width", w}, {"height", h}};
  m["hr_size"] = {{"width", w * signature.scale()}, {"height", h * signature.scale()}};
  m["per_frame"] = {
      "1. run selector.file with selector.inputs: this frame's rendering information and the previous frame's "
      "(on a first frame, after a cut or a resize: this frame's twice)",
      "2. read the int64 output 'pattern' (argmax of 'scores'): index into patterns",
      "3. run patterns[pattern].file with network.inputs; its output is network.output"};

  nlohmann::ordered_json network;
  network["format"] = enum_name(options.format);
  network["inputs"] = network_inputs_json(signature, net, w, h);
  network["output"] = {{"name", kExportOutput},
                       {"shape", dims_json({1, 3, h * signature.scale(), w * signature.scale()})},
                       {"content", "super-resolved RGB in [0,1] (not clamped)"}};
  network["size"] = options.format == ExportFormat::Onnx ? "fixed at lr_size" : "any (TorchScript)";
  m["network"] = network;

  nlohmann::ordered_json selector;
  selector["file"] = out.selector_file.filename().string();
  selector["format"] = "onnx";
  const auto info_shape = dims_json({1, c, h, w});
  selector["inputs"] = {
      {{"name", kSelectorInfoInput}, {"shape", info_shape}, {"content", "this frame's rendering information"}},
      {{"name", kSelectorPreviousInput},
       {"shape", info_shape},
       {"content", "the previous frame's rendering information; on a first frame the same tensor as render_info"}}};
  selector["channels"] = channel_rows_json(sampler_channels);
  selector["depth_encoding"] = enum_name(net.depth_encoding());
  selector["motion"] = {
      {"unit", "pixels at lr_size: a pixel at p was at p + motion in the previous frame"},
      {"normalization", "inside the file: dx / lr_width and dy / lr_height, each clamped to [-1, 1]"}};
  selector["grid"] = so.grid;
  selector["outputs"] = {
      {{"name", kSelectorScores}, {"type", "float32"}, {"shape", dims_json({1, patterns.size()})}},
      {{"name", kSelectorPattern}, {"type", "int64"}, {"shape", dims_json({1})}}};
  selector["macs"] = sampler.macs();
  selector["parameters"] = sampler.parameter_count();
  m["selector"] = selector;

  m["patterns"] = pattern_entries;
  m["latency_table"] = {
      {"lr_size", {{"width", model.latency.lr_width}, {"height", model.latency.lr_height}}},
      {"median_ms", model.latency.median_ms},
      {"measured_with", "cgsr's own CPU inference path on the machine that pruned the model (median per pattern); "
                        "relative costs, not this engine's timings"}};

  out.manifest_file = dir / kHybridManifestFile;
  write_file_atomic(out.manifest_file, m.dump(2) + "\n");
  out.manifest = std::move(m);
  return out;
}

HybridExport export_hybrid_file(const std::filesystem::path& model_file, const std::filesystem::path& dir, const ExportOptions& options) {
  const Model plain = load_model(model_file);
  if (!is_hybrid_model(plain.provenance))
    throw Error(model_file.string(), "not a hybrid-pruned model (no dynamic_pruning component in its provenance); "
                                     "export it as a plain network");
  return export_hybrid(load_hybrid_model(model_file), dir, options);
}

}  // namespace cgsr

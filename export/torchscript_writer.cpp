#include "export/torchscript_writer.h"

#include <torch/script.h>
#include <torch/torch.h>

#include <iomanip>
#include <regex>
#include <set>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "export/export_signature.h"

namespace cgsr {
namespace {

std::string attribute_name(const std::string& op_name, const std::string& role) {
  std::string name;
  for (char ch : op_name + "." + role) {
    if (ch == '.')
      name += "__";
    else
      name += ch;
  }
  static const std::regex identifier("[A-Za-z_][A-Za-z0-9_]*");
  if (!std::regex_match(name, identifier))
    throw Error("torchscript export: op '" + op_name + "'", "its name does not make a TorchScript attribute name");
  return name;
}

// A float literal TorchScript reads back to the same double.
std::string literal(double v) {
  std::ostringstream s;
  s << std::setprecision(17) << v;
  std::string text = s.str();
  if (text.find_first_of(".en") == std::string::npos) text += ".0";
  return text;
}

std::string int_pair(int64_t v) { return "[" + std::to_string(v) + ", " + std::to_string(v) + "]"; }

// One attribute to register: name, tensor, parameter (true) or buffer (false).
struct Attribute {
  std::string name;
  torch::Tensor value;
  bool parameter = true;
};

struct Generated {
  std::string source;
  std::vector<Attribute> attributes;
};

Generated generate(const graph::Graph& graph) {
  const ExportSignature signature = export_signature(graph);
  Generated out;
  std::set<std::string> used;
  const auto add_attribute = [&](const graph::Op& op, const std::string& role, const torch::Tensor& t) {
    Attribute a{attribute_name(op.name, role), t.detach().to(torch::kCPU, torch::kFloat).clone(), op.trainable};
    CGSR_CHECK(used.insert(a.name).second, "torchscript export: attribute '" + a.name + "' used twice");
    if (!torch::isfinite(a.value).all().item<bool>())
      throw Error("torchscript export: tensor '" + op.name + "." + role + "'", "contains NaN or infinite values");
    out.attributes.push_back(a);
    return "self." + a.name;
  };

  std::vector<std::string> names(graph.values.size());
  std::ostringstream src;
  src << "def forward(self";
  for (const auto& port : signature.inputs) {
    names[port.value] = port.name;
    src << ", " << port.name << ": Tensor";
  }
  src << ") -> Tensor:\n";
  for (const auto& op : graph.ops) {
    const std::string y = "v" + std::to_string(op.output);
    names[op.output] = y;
    const auto in = [&](size_t i) { return names.at(op.inputs.at(i)); };
    std::string expr;
    switch (op.kind) {
      case graph::OpKind::Conv: {
        const std::string w = add_attribute(op, "weight", op.weight);
        const std::string b = op.bias.defined() ? add_attribute(op, "bias", op.bias) : "None";
        expr = "torch.conv2d(" + in(0) + ", " + w + ", " + b + ", " + int_pair(op.stride) + ", " + int_pair(op.padding) +
               ", " + int_pair(op.dilation) + ", " + std::to_string(op.groups) + ")";
        break;
      }
      case graph::OpKind::Relu: expr = "torch.relu(" + in(0) + ")"; break;
      case graph::OpKind::Sigmoid: expr = "torch.sigmoid(" + in(0) + ")"; break;
      case graph::OpKind::LeakyRelu: expr = "torch.leaky_relu(" + in(0) + ", " + literal(op.negative_slope) + ")"; break;
      case graph::OpKind::PixelShuffle: expr = "torch.pixel_shuffle(" + in(0) + ", " + std::to_string(op.factor) + ")"; break;
      case graph::OpKind::Resize: {
        const std::string f = literal(static_cast<double>(op.factor));
        const std::string scales = "[" + f + ", " + f + "]";
        switch (op.mode) {
          case graph::ResizeMode::Nearest: expr = "torch.upsample_nearest2d(" + in(0) + ", None, " + scales + ")"; break;
          case graph::ResizeMode::Bilinear:
            expr = "torch.upsample_bilinear2d(" + in(0) + ", None, False, " + scales + ")";
            break;
          case graph::ResizeMode::Bicubic:
            expr = "torch.upsample_bicubic2d(" + in(0) + ", None, False, " + scales + ")";
            break;
        }
        break;
      }
      case graph::OpKind::AvgPool:
        expr = "torch.avg_pool2d(" + in(0) + ", " + int_pair(op.factor) + ", " + int_pair(op.factor) + ")";
        break;
      case graph::OpKind::ChannelAffine: {
        expr = in(0);
        if (op.scale.defined()) expr = expr + " * " + add_attribute(op, "scale", op.scale) + ".view([1, -1, 1, 1])";
        if (op.shift.defined()) expr = expr + " + " + add_attribute(op, "shift", op.shift) + ".view([1, -1, 1, 1])";
        break;
      }
      case graph::OpKind::Add: expr = in(0) + " + " + in(1); break;
      case graph::OpKind::Mul: expr = in(0) + " * " + in(1); break;
      case graph::OpKind::Concat: {
        expr = "torch.cat([";
        for (size_t i = 0; i < op.inputs.size(); ++i) expr += (i ? ", " : "") + in(i);
        expr += "], 1)";
        break;
      }
      case graph::OpKind::Sample: {
        // graph::apply_sample's grid, operation for operation (so the same float32 bits).
        const std::string source = in(0), off = in(1), r = std::to_string(op.factor);
        const auto centres = [&](const std::string& axis_name, int dim) {
          const std::string d = std::to_string(dim);
          src << "    " << y << "_" << axis_name << " = (torch.arange(" << off << ".size(" << d
              << ")).float() * 2 + 1) / " << r << " / " << source << ".size(" << d << ") - 1\n";
        };
        centres("x", 3);
        centres("y", 2);
        const std::string size = "[" + off + ".size(2), " + off + ".size(3)]";
        src << "    " << y << "_base = torch.stack([" << y << "_x.view([1, -1]).expand(" << size << "), " << y
            << "_y.view([-1, 1]).expand(" << size << ")], -1).unsqueeze(0)\n";
        src << "    " << y << "_scale = torch.full([2], 2.0) / torch.tensor([float(" << source << ".size(3)), float("
            << source << ".size(2))])\n";
        expr = "torch.grid_sampler(" + source + ", " + off + ".permute([0, 2, 3, 1]) * " + y + "_scale + " + y +
               "_base, " + std::to_string(graph::sample_interpolation(op.mode)) + ", 1, False)";
        break;
      }
      case graph::OpKind::AnyAbsAbove:
        expr = "(" + in(0) + ".abs().amax(1, True) > " + literal(op.threshold) + ").float()";
        break;
    }
    if (expr.empty())
      throw Error("torchscript export: op '" + op.name + "'",
                  std::string("the TorchScript writer does not know op kind '") + graph::op_kind_name(op.kind) + "'");
    src << "    " << y << " = " << expr << "  # " << op.name << "\n";
  }
  src << "    return " << names.at(signature.output.value) << "\n";
  out.source = src.str();
  return out;
}

}  // namespace

std::string torchscript_source(const graph::Graph& graph) { return generate(graph).source; }

torch::jit::Module torchscript_module(const graph::Graph& graph) {
  const Generated generated = generate(graph);
  torch::jit::Module module("__torch__.cgsr.SuperResolution");
  for (const auto& a : generated.attributes) {
    if (a.parameter)
      module.register_parameter(a.name, a.value, /*is_buffer=*/false);
    else
      module.register_buffer(a.name, a.value);
  }
  try {
    module.define(generated.source);
  } catch (const std::exception& e) {
    throw Error("torchscript export", std::string("the generated forward does not compile: ") + e.what(),
                ErrorKind::Internal);
  }
  module.eval();
  return module;
}

void write_torchscript(const std::filesystem::path& path, const graph::Graph& graph, const TorchScriptOptions& options) {
  torch::jit::Module module = torchscript_module(graph);
  torch::jit::ExtraFilesMap extra;
  for (const auto& [name, content] : options.extra_files) extra[name] = content;
  // In memory first: LibTorch's file writer throws from its destructor on a full disk.
  std::ostringstream bytes;
  module.save(bytes, extra);
  write_file_atomic(path, bytes.str());
}

torch::jit::Module load_torchscript(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) throw Error(path.string(), "no such file");
  try {
    auto module = torch::jit::load(path.string(), torch::kCPU);
    module.eval();
    return module;
  } catch (const c10::Error& e) {
    throw Error(path.string(), std::string("not a loadable TorchScript file: ") + e.what_without_backtrace());
  }
}

}  // namespace cgsr

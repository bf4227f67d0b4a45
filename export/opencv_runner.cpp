#include "export/opencv_runner.h"

#include <torch/torch.h>

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>

#include <cstring>

#include "core/error.h"
#include "core/tensor_checks.h"
#include "export/onnx_writer.h"

namespace cgsr {
namespace {

std::string declared_shape(const OnnxTensorInfo& info) {
  std::string s = "[";
  for (size_t i = 0; i < info.dims.size(); ++i)
    s += (i ? ", " : "") + (info.dims[i].value >= 0 ? std::to_string(info.dims[i].value) : info.dims[i].param);
  return s + "]";
}

cv::Mat to_blob(const torch::Tensor& t) {
  const auto c = t.detach().to(torch::kCPU, torch::kFloat).contiguous();
  std::vector<int> sizes(c.sizes().begin(), c.sizes().end());
  cv::Mat blob(static_cast<int>(sizes.size()), sizes.data(), CV_32F);
  std::memcpy(blob.ptr<float>(), c.data_ptr<float>(), static_cast<size_t>(c.numel()) * sizeof(float));
  return blob;
}

torch::Tensor from_blob(const cv::Mat& blob) {
  std::vector<int64_t> sizes(blob.size.p, blob.size.p + blob.dims);
  CGSR_CHECK(blob.type() == CV_32F && blob.isContinuous(), "OpenCV DNN returned a non-float or strided blob");
  auto t = torch::empty(sizes, torch::kFloat);
  std::memcpy(t.data_ptr<float>(), blob.ptr<float>(), static_cast<size_t>(t.numel()) * sizeof(float));
  return t;
}

}  // namespace

std::string opencv_dnn_unsupported_reason(const std::filesystem::path& onnx_file) {
  const OnnxModelInfo info = inspect_onnx_file(onnx_file);
  if (info.metadata_value("cgsr.precision") == "int8")
    return "OpenCV DNN 4.6 does not import DequantizeLinear with per-channel int8 weights, so it runs float32 "
           "exports only; this is an int8 (QDQ) export";
  if (info.dynamic())
    return "OpenCV DNN 4.6 imports DepthToSpace/Reshape only at the fixed size written in the file, so it runs "
           "fixed-size exports only; this is a --dynamic-size export (export again with a fixed --input size to run "
           "it in OpenCV DNN)";
  for (const auto& [type, count] : info.op_counts)
    if (type == "GridSample")
      return "OpenCV DNN 4.6 has no GridSample layer (ONNX opset 16), which this export samples by offsets with "
             "(SRPO's projection, rit.skip_at_jitter, history_out's warp)";
  return "";
}

NamedTensors run_opencv_dnn(const std::filesystem::path& onnx_file, const NamedTensors& inputs) {
  const std::string context = onnx_file.string() + " (OpenCV DNN)";
  const OnnxModelInfo info = inspect_onnx_file(onnx_file);
  if (const std::string why = opencv_dnn_unsupported_reason(onnx_file); !why.empty()) throw Error(context, why);
  for (const auto& declared : info.inputs) {
    const torch::Tensor t = find_tensor(inputs, declared.name);
    if (!t.defined()) throw Error(context, "input '" + declared.name + "' is missing");
    std::vector<int64_t> want;
    for (const auto& d : declared.dims) want.push_back(d.value);
    if (t.sizes().vec() != want)
      throw Error(context, "input '" + declared.name + "' must be " + declared_shape(declared) +
                               " as written in the file, got " + shape_string(t));
  }
  for (const auto& [name, t] : inputs)
    if (!info.find_input(name)) throw Error(context, "the model has no input '" + name + "'");
  try {
    cv::dnn::Net net = cv::dnn::readNetFromONNX(onnx_file.string());
    net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
    net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
    // The default (fused) network, as users get it: verification tests what they would run.
    for (const auto& declared : info.inputs) net.setInput(to_blob(find_tensor(inputs, declared.name)), declared.name);
    std::vector<std::string> names;
    for (const auto& o : info.outputs) names.push_back(o.name);
    std::vector<cv::Mat> blobs;
    net.forward(blobs, names);
    NamedTensors out;
    for (size_t i = 0; i < names.size(); ++i) out.emplace_back(names[i], from_blob(blobs.at(i)));
    return out;
  } catch (const cv::Exception& e) {
    throw Error(context, std::string("OpenCV: ") + e.what());
  }
}

std::string opencv_version() { return CV_VERSION; }

}  // namespace cgsr

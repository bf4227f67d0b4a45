#include "render_data/frame_files.h"

#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_group.h>
#include <torch/torch.h>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/image_header.h"
#include "core/image_io.h"
#include "core/tensor_checks.h"
#include "render_data/bsp_border_file.h"

namespace cgsr {
namespace fs = std::filesystem;

namespace {
std::string at_frame(int frame) { return "frame " + std::to_string(frame) + ": "; }

// Encoded bytes of one file kind (the tensor it stores).
std::vector<unsigned char> encode_kind(FileKind kind, const GBuffer& g) {
  switch (kind) {
    case FileKind::Color: return encode_image(".png", g.color, {8});
    case FileKind::Depth: return encode_image(".exr", torch::where(torch::isinf(g.depth), torch::zeros({}), g.depth), {32});
    case FileKind::Normal: return encode_image(".png", (g.normal + 1.0f) * 0.5f, {16});
    case FileKind::NormalAngle: return encode_image(".png", g.normal_angle, {16});
    case FileKind::Edge: return encode_image(".png", (g.edge > 0.5f).to(torch::kFloat32), {8});  // binary by contract
    case FileKind::Id: {
      if (g.object_id.max().item<int32_t>() >= 65535 || g.material_id.max().item<int32_t>() >= 65535)
        throw Error("id", "object and material ids must be below 65535 to be stored");
      const auto ids = torch::cat({g.object_id, g.material_id, torch::full_like(g.object_id, -1)}, 0);
      return encode_image(".png", (ids + 1).to(torch::kFloat32) / 65535.0f, {16});
    }
    case FileKind::Motion: return encode_image(".exr", torch::cat({g.motion, torch::zeros_like(g.motion[0]).unsqueeze(0)}, 0), {32});
  }
  return {};
}
}  // namespace

std::vector<size_t> write_frame_files(const fs::path& root, const Resolution& resolution, int frame, const GBuffer& g) {
  CGSR_CHECK(g.width == resolution.width && g.height == resolution.height, "G-buffer size does not match");
  const auto& kinds = all_file_kinds();
  std::vector<size_t> bytes(kinds.size());
  tbb::parallel_for(size_t(0), kinds.size(), [&](size_t i) {
    const fs::path path = frame_file(root, resolution, kinds[i], frame);
    fs::create_directories(path.parent_path());
    const auto data = encode_kind(kinds[i], g);
    write_file_atomic(path, std::string(data.begin(), data.end()));
    bytes[i] = data.size();
  });
  return bytes;
}

bool frame_complete(const fs::path& root, const std::vector<Resolution>& resolutions, int frame) {
  for (const auto& r : resolutions)
    for (FileKind k : all_file_kinds())
      if (!fs::exists(frame_file(root, r, k, frame))) return false;
  return true;
}

void check_image_size(const torch::Tensor& image, const Resolution& expected, const std::string& context, int frame) {
  if (image.size(-1) != expected.width || image.size(-2) != expected.height)
    throw Error(context, at_frame(frame) + "size " + std::to_string(image.size(-1)) + "x" + std::to_string(image.size(-2)) +
                             " does not match the resolution " + expected.name());
}

void check_finite(const torch::Tensor& values, const std::string& context, int frame, const char* what) {
  const auto bad = count_non_finite(values);
  if (bad.any())
    throw Error(context, at_frame(frame) + what + " has " + std::to_string(bad.nan) + " NaN and " +
                             std::to_string(bad.inf) + " infinite value(s)");
}

void check_unit_normals(const torch::Tensor& normal, const torch::Tensor& depth, const std::string& context, int frame) {
  const auto len = normal.to(torch::kFloat32).norm(2, 0, /*keepdim=*/true);
  const auto geometry = torch::isfinite(depth);
  const int64_t zero = (geometry & (len < 0.5f)).sum().item<int64_t>();
  if (zero > 0)
    throw Error(context, at_frame(frame) + std::to_string(zero) + " pixel(s) with geometry have zero-length normals");
}

const char* file_problem_name(FileProblem p) {
  switch (p) {
    case FileProblem::None: return "none";
    case FileProblem::Missing: return "missing";
    case FileProblem::Unreadable: return "unreadable";
    case FileProblem::WrongSize: return "wrong size";
    case FileProblem::NonFinite: return "NaN/Inf";
    case FileProblem::OutOfRange: return "out of range";
    case FileProblem::ZeroNormal: return "zero-length normals";
  }
  return "?";
}

DecodedFile decode_file(FileKind kind, const fs::path& path, int frame, const Resolution& expected,
                        const torch::Tensor& depth) {
  DecodedFile out;
  auto fail = [&](FileProblem p, const std::string& what) {
    out.value = torch::Tensor();
    out.problem = p;
    out.message = at_frame(frame) + what;
    return out;
  };
  if (!fs::exists(path)) return fail(FileProblem::Missing, "missing file");
  const int channels = kind == FileKind::Color || kind == FileKind::Normal || kind == FileKind::Id || kind == FileKind::Motion ? 3 : 1;
  torch::Tensor v;
  try {
    // The size its header declares first: a small file may declare a huge image.
    const ImageHeader header = read_image_header(path);
    if (header.width != expected.width || header.height != expected.height)
      return fail(FileProblem::WrongSize, "size " + std::to_string(header.width) + "x" + std::to_string(header.height) +
                                              " (from the " + header.format + " header; not decoded) does not match "
                                              "the resolution " + expected.name());
    v = read_image(path, {channels, expected.width, expected.height});
  } catch (const Error& e) {
    return fail(FileProblem::Unreadable, e.message());
  }
  if (v.size(2) != expected.width || v.size(1) != expected.height)
    return fail(FileProblem::WrongSize, "size " + std::to_string(v.size(2)) + "x" + std::to_string(v.size(1)) +
                                            " does not match the resolution " + expected.name());
  const auto bad = count_non_finite(v);
  if (bad.any())
    return fail(FileProblem::NonFinite, std::to_string(bad.nan) + " NaN and " + std::to_string(bad.inf) + " infinite value(s)");
  switch (kind) {
    case FileKind::Color: out.value = (v * 255.0f).round_().to(torch::kUInt8); break;
    case FileKind::Depth:
      if ((v < 0).any().item<bool>()) return fail(FileProblem::OutOfRange, "negative depth values");
      out.value = torch::where(v == 0, torch::full({}, std::numeric_limits<float>::infinity()), v);
      break;
    case FileKind::Normal: {
      auto n = v * 2.0f - 1.0f;
      if (depth.defined()) {
        const auto geometry = torch::isfinite(depth);
        const int64_t zero = (geometry & (n.norm(2, 0, true) < 0.5f)).sum().item<int64_t>();
        if (zero > 0) return fail(FileProblem::ZeroNormal, std::to_string(zero) + " pixel(s) with geometry have zero-length normals");
        n = torch::where(geometry, n, torch::zeros({}));
      }
      out.value = n.to(torch::kFloat16);
      break;
    }
    case FileKind::NormalAngle: out.value = v.to(torch::kFloat16); break;
    case FileKind::Edge: {
      // Compare the stored bytes: 255 * (1/255) need not be exactly 1 in float.
      const auto stored = (v * 255.0f).round_();
      const int64_t other = ((stored != 0) & (stored != 255)).sum().item<int64_t>();
      if (other > 0) return fail(FileProblem::OutOfRange, std::to_string(other) + " edge value(s) other than 0 and 255");
      out.value = (stored > 0).to(torch::kUInt8);
      break;
    }
    case FileKind::Id: out.value = (v.slice(0, 0, 2) * 65535.0f).round_().to(torch::kInt32) - 1; break;
    case FileKind::Motion: out.value = v.slice(0, 0, 2).contiguous(); break;
  }
  return out;
}

namespace {
torch::Tensor decode_or_throw(FileKind kind, const fs::path& path, int frame, const Resolution& expected,
                              const torch::Tensor& depth = {}) {
  DecodedFile d = decode_file(kind, path, frame, expected, depth);
  if (d.problem != FileProblem::None) throw Error(path.string(), d.message);
  return d.value;
}
}  // namespace

torch::Tensor read_color_file(const fs::path& path, int frame, const Resolution& expected) {
  return decode_or_throw(FileKind::Color, path, frame, expected);
}
torch::Tensor read_depth_file(const fs::path& path, int frame, const Resolution& expected) {
  return decode_or_throw(FileKind::Depth, path, frame, expected);
}
torch::Tensor read_normal_file(const fs::path& path, int frame, const Resolution& expected, const torch::Tensor& depth) {
  return decode_or_throw(FileKind::Normal, path, frame, expected, depth);
}
torch::Tensor read_normal_angle_file(const fs::path& path, int frame, const Resolution& expected) {
  return decode_or_throw(FileKind::NormalAngle, path, frame, expected);
}
torch::Tensor read_edge_file(const fs::path& path, int frame, const Resolution& expected) {
  return decode_or_throw(FileKind::Edge, path, frame, expected);
}
torch::Tensor read_id_file(const fs::path& path, int frame, const Resolution& expected) {
  return decode_or_throw(FileKind::Id, path, frame, expected);
}
torch::Tensor read_motion_file(const fs::path& path, int frame, const Resolution& expected) {
  return decode_or_throw(FileKind::Motion, path, frame, expected);
}

Frame read_dataset_frame(const fs::path& root, const DatasetManifest& m, int frame, size_t res,
                         const std::vector<RenderChannel>& channels) {
  if (frame < 0 || frame >= m.frames)
    throw Error(root.string(), "frame " + config::out_of_range(frame, 0, m.frames - 1));
  const Resolution& r = m.resolutions.at(res);
  auto want = [&](RenderChannel c) { return std::find(channels.begin(), channels.end(), c) != channels.end(); };
  Frame f;
  f.width = r.width;
  f.height = r.height;
  if (res == 0 && !m.jitter_offsets.empty()) f.jitter = m.jitter_offsets.at(static_cast<size_t>(frame));
  // The files decode independently (normals after depth): one task each, so a 1080p frame's
  // PNG and EXR decodes overlap instead of adding up.
  tbb::task_group files;
  files.run([&] { f.color = read_color_file(m.file(root, frame, res, FileKind::Color), frame, r); });
  if (want(RenderChannel::Depth) || want(RenderChannel::Normal))
    files.run([&] {
      const auto depth = read_depth_file(m.file(root, frame, res, FileKind::Depth), frame, r);
      if (want(RenderChannel::Depth)) f.depth = depth;
      if (want(RenderChannel::Normal))
        f.normal = read_normal_file(m.file(root, frame, res, FileKind::Normal), frame, r, depth);
    });
  if (want(RenderChannel::NormalAngle))
    files.run([&] { f.normal_angle = read_normal_angle_file(m.file(root, frame, res, FileKind::NormalAngle), frame, r); });
  if (want(RenderChannel::Edge)) files.run([&] { f.edge = read_edge_file(m.file(root, frame, res, FileKind::Edge), frame, r); });
  if (want(RenderChannel::Motion))
    files.run([&] { f.motion = read_motion_file(m.file(root, frame, res, FileKind::Motion), frame, r); });
  if (m.bsp_border_depth > 0 && res == 0)  // small files: read whenever the data set has them
    files.run([&] {
      f.bsp_border = std::make_shared<const BspBorderImage>(read_bsp_border_file(bsp_border_file(root, r, frame), frame, r));
    });
  files.wait();  // rethrows the first decoding error
  return f;
}

}  // namespace cgsr

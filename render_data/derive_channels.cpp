#include "render_data/derive_channels.h"

#include <oneapi/tbb/parallel_for.h>
#include <torch/torch.h>

#include <cmath>

#include "core/error.h"
#include "render_data/vec_math.h"

namespace cgsr {
namespace {

// Pixel-to-view-space mapping of a pinhole camera: view ray (u, v, -1) * depth.
struct Pinhole {
  double cx, cy, f;
  Pinhole(int W, int H, double vfov) : cx(W / 2.0), cy(H / 2.0), f(H / 2.0 / std::tan(vfov * kPi / 360.0)) {}
  Vec3 point(int i, int j, float z) const {
    return {static_cast<float>((j + 0.5 - cx) / f * z), static_cast<float>((cy - (i + 0.5)) / f * z), -z};
  }
};
}  // namespace

bool derivable(RenderChannel c) {
  return c == RenderChannel::Edge || c == RenderChannel::Normal || c == RenderChannel::NormalAngle;
}

torch::Tensor normals_from_depth(const torch::Tensor& depth, double vfov) {
  if (!(vfov > 0 && vfov < 180)) throw Error("derive normals", "vertical field of view must be in (0, 180) degrees");
  const auto d = (depth.dim() == 3 ? depth[0] : depth).to(torch::kFloat32).contiguous();
  const int H = static_cast<int>(d.size(0)), W = static_cast<int>(d.size(1));
  const float* z = d.data_ptr<float>();
  auto out = torch::zeros({3, H, W}, torch::kFloat32);
  float* n = out.data_ptr<float>();
  const size_t plane = static_cast<size_t>(H) * W;
  const Pinhole cam(W, H, vfov);
  auto valid = [&](int i, int j) { return i >= 0 && j >= 0 && i < H && j < W && std::isfinite(z[i * W + j]) && z[i * W + j] > 0; };
  tbb::parallel_for(0, H, [&](int i) {
    for (int j = 0; j < W; ++j) {
      if (!valid(i, j)) continue;
      const float zc = z[i * W + j];
      const Vec3 p = cam.point(i, j, zc);
      // One-sided difference along an axis towards the neighbour whose depth is closer to ours.
      auto tangent = [&](int di, int dj, Vec3& t) {
        const bool fwd = valid(i + di, j + dj), back = valid(i - di, j - dj);
        if (!fwd && !back) return false;
        bool use_fwd = fwd;
        if (fwd && back)
          use_fwd = std::abs(z[(i + di) * W + j + dj] - zc) <= std::abs(z[(i - di) * W + j - dj] - zc);
        t = use_fwd ? cam.point(i + di, j + dj, z[(i + di) * W + j + dj]) - p
                    : p - cam.point(i - di, j - dj, z[(i - di) * W + j - dj]);
        return true;
      };
      Vec3 tx, ty, normal;
      if (tangent(0, 1, tx) && tangent(1, 0, ty)) normal = normalize(cross(ty, tx));
      if (length(normal) == 0) normal = normalize(-p);  // isolated pixel: face the camera
      if (dot(normal, -p) < 0) normal = -normal;
      const size_t k = static_cast<size_t>(i) * W + j;
      n[k] = normal.x;
      n[plane + k] = normal.y;
      n[2 * plane + k] = normal.z;
    }
  });
  return out;
}

torch::Tensor normal_angle_from_normals(const torch::Tensor& normal, double vfov) {
  const auto nrm = normal.to(torch::kFloat32).contiguous();
  const int H = static_cast<int>(nrm.size(1)), W = static_cast<int>(nrm.size(2));
  const Pinhole cam(W, H, vfov);
  // Direction to the camera through each pixel centre: -(u, v, -1) normalized.
  auto j = (torch::arange(W, torch::kFloat64) + 0.5 - cam.cx) / cam.f;
  auto i = (cam.cy - (torch::arange(H, torch::kFloat64) + 0.5)) / cam.f;
  auto u = j.view({1, W}).expand({H, W}), v = i.view({H, 1}).expand({H, W});
  auto to_cam = torch::stack({-u, -v, torch::ones({H, W}, torch::kFloat64)}, 0);
  to_cam = (to_cam / to_cam.norm(2, 0, true)).to(torch::kFloat32);
  const auto cos_a = (nrm * to_cam).sum(0, true).clamp(-1, 1);
  const auto angle = (torch::acos(cos_a) / (kPi / 2)).clamp(0, 1);
  return torch::where(nrm.abs().sum(0, true) > 0, angle, torch::zeros({}));
}

void derive_channels(Frame& f, const std::vector<RenderChannel>& derive, double vfov, const EdgeSettings& edges) {
  auto wanted = [&](RenderChannel c) { return std::find(derive.begin(), derive.end(), c) != derive.end() && !f.has(c); };
  for (auto c : derive)
    if (!f.has(c) && !derivable(c))
      throw Error("derive channels", "'" + channel_name(c) + "' cannot be derived (only edge, normal, normal_angle)");
  const bool any = wanted(RenderChannel::Edge) || wanted(RenderChannel::Normal) || wanted(RenderChannel::NormalAngle);
  if (!any) return;
  if (!f.depth.defined()) throw Error("derive channels", "deriving channels needs depth, which the frame does not have");
  torch::Tensor normal = f.normal.defined() ? f.normal.to(torch::kFloat32) : torch::Tensor();
  // Creases come from stored normals, or from normals derived from exact depth: normals of a
  // quantised depth staircase turn at every step.
  torch::Tensor crease_normal = normal;
  if (wanted(RenderChannel::Normal) || (wanted(RenderChannel::NormalAngle) && !normal.defined())) {
    normal = normals_from_depth(f.depth, vfov);
    if (wanted(RenderChannel::Normal)) f.normal = normal.to(torch::kFloat16);
    if (wanted(RenderChannel::Normal) && f.depth_precision.exact()) crease_normal = normal;
  }
  if (wanted(RenderChannel::NormalAngle)) f.normal_angle = normal_angle_from_normals(normal, vfov).to(torch::kFloat16);
  if (wanted(RenderChannel::Edge))
    f.edge = detect_edges(f.depth, crease_normal, {}, edges, f.depth_precision).to(torch::kUInt8);
}

}  // namespace cgsr

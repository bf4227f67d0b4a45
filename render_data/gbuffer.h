#pragma once
// One rendered frame at one resolution: colour and every G-buffer channel, as CPU tensors.
// Channel meanings follow render_channels.h; depth here is LINEAR (normalize_depth makes the
// network's form, with the near/far of the camera path).

#include <torch/types.h>

#include <cstdint>

namespace cgsr {

struct GBuffer {
  int width = 0, height = 0;
  torch::Tensor color;         // float32 [3,H,W], sRGB-encoded, in [0,1]
  torch::Tensor depth;         // float32 [1,H,W], linear view depth (-z_view), +inf where no geometry
  torch::Tensor normal;        // float32 [3,H,W], view-space unit normal facing the camera; 0 on sky
  torch::Tensor normal_angle;  // float32 [1,H,W], angle to the camera direction / 90 deg, in [0,1]
  torch::Tensor object_id;     // int32 [1,H,W], Mesh::object_id; -1 on sky
  torch::Tensor material_id;   // int32 [1,H,W], Mesh::material; -1 on sky
  torch::Tensor edge;          // float32 [1,H,W], 0 or 1 (edges.h)
  torch::Tensor motion;        // float32 [2,H,W], (dx, dy) pixels: the pixel was at p + motion before
  // Pixels whose point was not in front of the previous camera's near plane: no previous pixel,
  // so their motion is 0 (render_channels.h). Not stored in the data set; the render reports it.
  int64_t motion_rejected = 0;
  // Pixels whose previous position lay beyond the guard band one image size around the previous
  // frame: their motion is cut there, keeping its direction (render_channels.h).
  int64_t motion_clamped = 0;
};

}  // namespace cgsr

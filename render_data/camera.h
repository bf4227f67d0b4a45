#pragma once
// The camera of one frame at one resolution: view and projection matrices and the mapping from
// clip space to pixel coordinates.
//
// Spaces:   world --view--> view space (camera at the origin, x right, y up, looking down -z)
//           --projection--> clip space (OpenGL convention, w = -z_view = linear view depth)
//           --divide by w--> NDC [-1,1]^2 --viewport--> pixel coordinates.
// Pixel coordinates: x right, y down, (0,0) is the top-left corner of the image; pixel (i, j)
// (row i, column j) covers [j, j+1) x [i, i+1) and is sampled at its centre (j + 0.5, i + 0.5).
// NDC maps to the whole image at every resolution, so resolutions share one frustum and an HR
// pixel centre (j + 0.5) lands on LR coordinate (j + 0.5) / s (docs/design.md, align_corners=False).

#include "render_data/scene.h"
#include "render_data/vec_math.h"

namespace cgsr {

struct FrameCamera {
  CameraPose pose;
  int width = 0, height = 0;
  float near_plane = 0.05f, far_plane = 500.0f;
  Mat4 view;             // world -> view
  Mat4 projection;       // view -> clip
  Mat4 view_projection;  // world -> clip
  Vec3 right, up, forward;  // world-space camera axes
  float focal_px = 0;       // focal length in pixels (same horizontally and vertically)
  Vec2 jitter{0, 0};        // sub-pixel offset of the projection (jitter.h): content moves by it
};

// `jitter`: pixels the projection moves every point by (jitter.h), in the projection matrix so
// rasterization, the G-buffer and pixel_ray all see it.
FrameCamera make_frame_camera(const CameraPose& pose, int width, int height, float near_plane, float far_plane,
                              Vec2 jitter = {0, 0});

// Clip space -> pixel coordinates (x right, y down). Requires clip.w > 0.
inline Vec2 clip_to_pixel(const FrameCamera& cam, Vec4 clip) {
  const float inv_w = 1.0f / clip.w;
  return {(clip.x * inv_w + 1.0f) * 0.5f * cam.width, (1.0f - clip.y * inv_w) * 0.5f * cam.height};
}

// Projects a world point to pixel coordinates; false when it is not in front of the camera
// (view depth <= 0). `view_depth` receives -z_view.
bool project_to_pixel(const FrameCamera& cam, Vec3 world, Vec2& pixel, float& view_depth);

// World-space direction of the ray through pixel coordinates (x, y) (not normalized; its
// component along `forward` is 1, so a point at view depth d is position + d * ray).
Vec3 pixel_ray(const FrameCamera& cam, float x, float y);

}  // namespace cgsr

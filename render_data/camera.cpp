#include "render_data/camera.h"

#include <cmath>

namespace cgsr {
namespace {
constexpr float kDegToRad = 3.14159265358979f / 180.0f;
}

FrameCamera make_frame_camera(const CameraPose& pose, int width, int height, float near_plane, float far_plane,
                              Vec2 jitter) {
  FrameCamera cam;
  cam.jitter = jitter;
  cam.pose = pose;
  cam.width = width;
  cam.height = height;
  cam.near_plane = near_plane;
  cam.far_plane = far_plane;

  // World-space camera axes from yaw (about +y), pitch (about the right axis), roll (about forward).
  const float yaw = pose.yaw * kDegToRad, pitch = pose.pitch * kDegToRad, roll = pose.roll * kDegToRad;
  const Vec3 forward{-std::sin(yaw) * std::cos(pitch), std::sin(pitch), -std::cos(yaw) * std::cos(pitch)};
  const Vec3 right0{std::cos(yaw), 0.0f, -std::sin(yaw)};
  const Vec3 up0 = cross(right0, forward);
  cam.right = right0 * std::cos(roll) + up0 * std::sin(roll);
  cam.up = up0 * std::cos(roll) - right0 * std::sin(roll);
  cam.forward = forward;

  // View matrix: rows are the camera axes (x = right, y = up, z = -forward), then the translation.
  Mat4 v;
  const Vec3 rows[3] = {cam.right, cam.up, -forward};
  for (int r = 0; r < 3; ++r) {
    v.m[0][r] = rows[r].x;
    v.m[1][r] = rows[r].y;
    v.m[2][r] = rows[r].z;
    v.m[3][r] = -dot(rows[r], pose.position);
  }
  cam.view = v;

  // Perspective projection (OpenGL): clip.w = -z_view; square pixels, vertical FOV given.
  const float fy = 1.0f / std::tan(0.5f * pose.vfov * kDegToRad);
  const float fx = fy * static_cast<float>(height) / static_cast<float>(width);
  Mat4 p;
  p.m[0][0] = fx;
  p.m[1][1] = fy;
  p.m[2][2] = -(far_plane + near_plane) / (far_plane - near_plane);
  p.m[3][2] = -2.0f * far_plane * near_plane / (far_plane - near_plane);
  p.m[2][3] = -1.0f;
  p.m[3][3] = 0.0f;
  // NDC offset times w (= -z_view): pixel x grows with NDC x, pixel y shrinks with NDC y. Left
  // untouched without jitter, so unjittered renders keep their bytes.
  if (jitter.x != 0) p.m[2][0] = -2.0f * jitter.x / static_cast<float>(width);
  if (jitter.y != 0) p.m[2][1] = 2.0f * jitter.y / static_cast<float>(height);
  cam.projection = p;
  cam.view_projection = p * v;
  cam.focal_px = 0.5f * static_cast<float>(height) * fy;
  return cam;
}

bool project_to_pixel(const FrameCamera& cam, Vec3 world, Vec2& pixel, float& view_depth) {
  const Vec4 clip = cam.view_projection * Vec4{world.x, world.y, world.z, 1.0f};
  view_depth = clip.w;
  if (!(clip.w > 0)) return false;
  pixel = clip_to_pixel(cam, clip);
  return true;
}

Vec3 pixel_ray(const FrameCamera& cam, float x, float y) {
  const float u = (x - cam.jitter.x - 0.5f * cam.width) / cam.focal_px;
  const float v = (0.5f * cam.height - (y - cam.jitter.y)) / cam.focal_px;
  return cam.forward + cam.right * u + cam.up * v;
}

}  // namespace cgsr

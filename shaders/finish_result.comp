#version 460
#extension GL_GOOGLE_include_directive : require
// The result as the user sees it (backend_cpu/finish_result.cpp, backend.hpp finishResult):
// unsolved pixels the quiet NaN in every output, the valid mask and z.
#include "common.glsl"

layout(push_constant) uniform PC {
  FBuf valid, z, radial, points, disparity, warp, confidence;
  int width, height;
} pc;

void main() {
  const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  const float r = pc.radial.v[i], u = pc.disparity.v[i], wx = pc.warp.v[2 * i], wy = pc.warp.v[2 * i + 1];
  if (!isnan(r) && !isnan(u) && !isinf(u) && !isnan(wx) && !isinf(wx) && !isnan(wy) && !isinf(wy)) {
    pc.valid.v[i] = 1.0;
    pc.z.v[i] = isinf(r) ? r : pc.points.v[3 * i + 2];
    return;
  }
  const float nan = quietNaN();
  pc.valid.v[i] = 0.0;
  pc.z.v[i] = nan;
  pc.radial.v[i] = nan;
  pc.disparity.v[i] = nan;
  pc.confidence.v[i] = nan;
  pc.warp.v[2 * i] = nan;
  pc.warp.v[2 * i + 1] = nan;
  for (int c = 0; c < 3; ++c) pc.points.v[3 * i + c] = nan;
}

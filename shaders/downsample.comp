#version 460
#extension GL_GOOGLE_include_directive : require
// dst = src smoothed by a Gaussian of sigma = scale / 2 and decimated, pixel-centre aware
// (backend_cpu/resample.cpp downsample).
#include "common.glsl"

layout(push_constant) uniform PC {
  FBuf dst, src;
  int w, h, nc, sw, sh;
  int radius;
  float scale, sigma;
} pc;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.w || y >= pc.h) return;
  const float cy = (float(y) + 0.5) * pc.scale - 0.5;
  const float cx = (float(x) + 0.5) * pc.scale - 0.5;
  const int fy = int(floor(cy)), fx = int(floor(cx));
  for (int c = 0; c < pc.nc; ++c) {
    float sum = 0.0, weights = 0.0;
    for (int j = fy - pc.radius + 1; j <= fy + pc.radius; ++j)
      for (int i = fx - pc.radius + 1; i <= fx + pc.radius; ++i) {
        float dx = float(i) - cx, dy = float(j) - cy;
        float wgt = exp(-(dx * dx + dy * dy) / (2.0 * pc.sigma * pc.sigma));
        int sx = min(max(i, 0), pc.sw - 1), sy = min(max(j, 0), pc.sh - 1);
        sum += wgt * pc.src.v[idx(pc.sw, pc.nc, sx, sy, c)];
        weights += wgt;
      }
    pc.dst.v[idx(pc.w, pc.nc, x, y, c)] = sum / weights;
  }
}

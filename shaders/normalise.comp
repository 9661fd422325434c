#version 460
#extension GL_GOOGLE_include_directive : require
// Local contrast normalisation, pass 2 (backend_cpu/normalise.cpp): the moments summed
// down the column (rows outside the image skipped), then
// dst = (I - mean) / sqrt(max(0, var) + eps^2); 0 outside the mask. `precise` as pass 1.
#include "normalise.glsl"

layout(push_constant) uniform PC {
  FBuf dst, moments, src, mask;
  NormaliseParamsRef prm;
  int w, h;
} pc;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.w || y >= pc.h) return;
  if (!masked(pc.mask, pc.w, pc.h, x, y)) {
    pc.dst.v[y * pc.w + x] = 0.0;
    return;
  }
  int r = pc.prm.radius;
  precise float s0 = 0.0, s1 = 0.0, s2 = 0.0;
  for (int j = -r; j <= r; ++j) {
    if (y + j < 0 || y + j >= pc.h) continue;
    float t = pc.prm.taps[j + r];
    int o = idx(pc.w, 3, x, y + j, 0);
    s0 += t * pc.moments.v[o + 0];
    s1 += t * pc.moments.v[o + 1];
    s2 += t * pc.moments.v[o + 2];
  }
  float eps = pc.prm.epsilon;
  precise float mean = s1 / s0;
  precise float variance = max(0.0, s2 / s0 - mean * mean);
  precise float value = (pc.src.v[y * pc.w + x] - mean) / sqrt(variance + eps * eps);
  pc.dst.v[y * pc.w + x] = value;
}

#version 460
#extension GL_GOOGLE_include_directive : require
// Local contrast normalisation, pass 1 (backend_cpu/normalise.cpp): the masked, weighted
// sums of 1, I and I^2 along the row, into the 3-channel moments. Summed in the oracle's
// order and `precise`, so that no multiply-add is fused.
#include "normalise.glsl"

layout(push_constant) uniform PC {
  FBuf moments, src, mask;
  NormaliseParamsRef prm;
  int w, h;
} pc;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.w || y >= pc.h) return;
  int r = pc.prm.radius;
  precise float s0 = 0.0, s1 = 0.0, s2 = 0.0;
  for (int i = -r; i <= r; ++i) {
    if (!masked(pc.mask, pc.w, pc.h, x + i, y)) continue;
    float t = pc.prm.taps[i + r], v = pc.src.v[y * pc.w + x + i];
    s0 += t;
    s1 += t * v;
    s2 += t * (v * v);
  }
  int o = idx(pc.w, 3, x, y, 0);
  pc.moments.v[o + 0] = s0;
  pc.moments.v[o + 1] = s1;
  pc.moments.v[o + 2] = s2;
}

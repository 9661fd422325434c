#version 460
#extension GL_GOOGLE_include_directive : require
// dst(x) = src(x + flow(x)), bilinear, clamped to the image edge (backend_cpu/warp.cpp).
#include "sampling.glsl"

layout(push_constant) uniform PC {
  FBuf dst, src, flow;
  int w, h, nc;     // dst / flow size; dst and src channels
  int sw, sh;       // src size
} pc;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.w || y >= pc.h) return;
  float sx = float(x) + pc.flow.v[idx(pc.w, 2, x, y, 0)];
  float sy = float(y) + pc.flow.v[idx(pc.w, 2, x, y, 1)];
  for (int c = 0; c < pc.nc; ++c) pc.dst.v[idx(pc.w, pc.nc, x, y, c)] = sampleBilinear(pc.src, pc.sw, pc.sh, pc.nc, c, sx, sy);
}

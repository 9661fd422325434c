#version 460
#extension GL_GOOGLE_include_directive : require
// du = clamp(u - u0, +-duMax); u = u0 + du; w += du * tangent at masked pixels
// (backend_cpu/accumulate.cpp).
#include "common.glsl"

layout(push_constant) uniform PC {
  FBuf u, w, u0, tangent, mask;
  int width, height;
  float duMax;
} pc;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height || !masked(pc.mask, pc.width, pc.height, x, y)) return;
  const int i = y * pc.width + x;
  float du = min(max(pc.u.v[i] - pc.u0.v[i], -pc.duMax), pc.duMax);
  pc.u.v[i] = pc.u0.v[i] + du;
  pc.w.v[2 * i] += du * pc.tangent.v[2 * i];
  pc.w.v[2 * i + 1] += du * pc.tangent.v[2 * i + 1];
}

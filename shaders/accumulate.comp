#version 460
#extension GL_GOOGLE_include_directive : require
// du = clamp(u - u0, +-duMax); u = u0 + du; w += du * tangent at masked pixels
// (backend_cpu/accumulate.cpp).
#include "common.glsl"

// w and tangent hold two channels a pixel (buffers start 16-byte aligned: memory.cpp).
layout(buffer_reference, std430, buffer_reference_align = 8) buffer V2Buf { vec2 v[]; };

layout(push_constant) uniform PC {
  FBuf u, w, u0, tangent, mask;
  int width, height;
  float duMax;
} pc;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height || !masked(pc.mask, pc.width, pc.height, x, y)) return;
  const int i = y * pc.width + x;
  // Every load before the first store: the compiler cannot tell the buffers apart, so a
  // load after a store would wait for it (three trips to memory instead of one; most
  // calls are on the small levels, where those latencies are the kernel's time).
  const float u = pc.u.v[i], u0 = pc.u0.v[i];
  const vec2 w = V2Buf(pc.w).v[i], tangent = V2Buf(pc.tangent).v[i];
  float du = min(max(u - u0, -pc.duMax), pc.duMax);
  pc.u.v[i] = u0 + du;
  V2Buf(pc.w).v[i] = vec2(w.x + du * tangent.x, w.y + du * tangent.y);
}

#version 460
#extension GL_GOOGLE_include_directive : require
// dst = valueScale * src resampled bilinearly to the finer grid (backend_cpu/resample.cpp).
#include "sampling.glsl"

layout(push_constant) uniform PC {
  FBuf dst, src;
  int w, h, nc, sw, sh;
  float scale, valueScale;
} pc;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.w || y >= pc.h) return;
  const float sy = (float(y) + 0.5) / pc.scale - 0.5;
  const float sx = (float(x) + 0.5) / pc.scale - 0.5;
  for (int c = 0; c < pc.nc; ++c)
    pc.dst.v[idx(pc.w, pc.nc, x, y, c)] = pc.valueScale * sampleBilinear(pc.src, pc.sw, pc.sh, pc.nc, c, sx, sy);
}

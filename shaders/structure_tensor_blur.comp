#version 460
#extension GL_GOOGLE_include_directive : require
// Structure tensor, passes 1 and 2: separable Gaussian blur of the image with clamp to
// edge (backend_cpu/structure_tensor.cpp blur). dir 0 blurs rows, 1 columns. The taps are
// computed as the oracle computes them: exp(-i^2 / (2 sigma^2)) normalised by their sum.
#include "common.glsl"

layout(push_constant) uniform PC {
  FBuf dst, src;
  int w, h, radius, dir;
  float sigma;
} pc;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.w || y >= pc.h) return;
  float sum = 0.0;
  for (int i = -pc.radius; i <= pc.radius; ++i) sum += exp(-float(i * i) / (2.0 * pc.sigma * pc.sigma));
  float s = 0.0;
  for (int i = -pc.radius; i <= pc.radius; ++i) {
    float tap = exp(-float(i * i) / (2.0 * pc.sigma * pc.sigma)) / sum;
    int sx = pc.dir == 0 ? min(max(x + i, 0), pc.w - 1) : x;
    int sy = pc.dir == 0 ? y : min(max(y + i, 0), pc.h - 1);
    s += tap * pc.src.v[sy * pc.w + sx];
  }
  pc.dst.v[y * pc.w + x] = s;
}

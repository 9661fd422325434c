#version 460
#extension GL_GOOGLE_include_directive : require
// The estimate one pyramid level finer: bilinear, except across the coarse estimate's
// depth edges, where each fine pixel takes the coarse neighbour whose displacement its
// images confirm (backend_cpu/upsample_estimate.cpp, backend.hpp upsampleEstimate).
#include "sampling.glsl"

layout(push_constant) uniform PC {
  FBuf u, w, coarseU, coarseW, n0, n1, mask;
  int width, height, coarseWidth, coarseHeight, radius;
  float scale, edge;
} pc;

float windowMismatch(int x, int y, float shiftX, float shiftY) {
  float sum = 0.0;
  for (int dy = -pc.radius; dy <= pc.radius; ++dy)
    for (int dx = -pc.radius; dx <= pc.radius; ++dx) {
      const int qx = min(max(x + dx, 0), pc.width - 1), qy = min(max(y + dy, 0), pc.height - 1);
      sum += abs(pc.n0.v[qy * pc.width + qx] -
                 sampleBilinear(pc.n1, pc.width, pc.height, 1, 0, float(qx) + shiftX, float(qy) + shiftY));
    }
  return sum;
}

void main() {
  const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const float s = pc.scale;
  const int cw = pc.coarseWidth, ch = pc.coarseHeight;
  const float cx = (float(x) + 0.5) / s - 0.5, cy = (float(y) + 0.5) / s - 0.5;
  float u = s * sampleBilinear(pc.coarseU, cw, ch, 1, 0, cx, cy);
  float wx = s * sampleBilinear(pc.coarseW, cw, ch, 2, 0, cx, cy);
  float wy = s * sampleBilinear(pc.coarseW, cw, ch, 2, 1, cx, cy);
  if (masked(pc.mask, pc.width, pc.height, x, y)) {
    const int ix = min(max(int(floor(cx)), 0), cw - 2), iy = min(max(int(floor(cy)), 0), ch - 2);
    float lowest = s * pc.coarseU.v[iy * cw + ix], highest = lowest;
    for (int k = 1; k < 4; ++k) {
      const float v = s * pc.coarseU.v[(iy + k / 2) * cw + ix + k % 2];
      lowest = min(lowest, v);
      highest = max(highest, v);
    }
    if (highest - lowest >= pc.edge) {
      int best = 0;
      float bestMismatch = 0.0;
      for (int k = 0; k < 4; ++k) {
        const int c = (iy + k / 2) * cw + ix + k % 2;
        const float m = windowMismatch(x, y, s * pc.coarseW.v[2 * c], s * pc.coarseW.v[2 * c + 1]);
        if (k == 0 || m < bestMismatch) {
          best = k;
          bestMismatch = m;
        }
      }
      const int c = (iy + best / 2) * cw + ix + best % 2;
      u = s * pc.coarseU.v[c];
      wx = s * pc.coarseW.v[2 * c];
      wy = s * pc.coarseW.v[2 * c + 1];
    }
  }
  const int i = y * pc.width + x;
  pc.u.v[i] = u;
  pc.w.v[2 * i] = wx;
  pc.w.v[2 * i + 1] = wy;
}

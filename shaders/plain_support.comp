#version 460
#extension GL_GOOGLE_include_directive : require
// The most confident masked full-resolution pixel under each coarse pixel
// (backend_cpu/plain_fill.cpp plainSupport, backend.hpp): X, Y, w and confidence, or
// 0, 0, 0, 0, -1 where the block has none. Blocks by integer arithmetic, as the oracle.
#include "common.glsl"

layout(push_constant) uniform PC {
  FBuf support, confidence, w, mask, levelImage, levelMask;
  int width, height, fullWidth, fullHeight;  // the support's grid, then the full one
} pc;

int coarseOf(int X, int coarse, int full) { return ((2 * X + 1) * coarse) / (2 * full); }

int blockStart(int c, int coarse, int full) {
  int X = max(0, (c * full) / coarse - 1);
  while (X < full && coarseOf(X, coarse, full) < c) ++X;
  return X;
}

// backend_cpu/plain_fill.cpp windowVariance: the same sums in the same order, `precise`.
float windowVariance(int x, int y) {
  const int r = 2, W = pc.width, H = pc.height;
  if (!masked(pc.levelMask, W, H, x, y)) return -1.0;
  precise float n = 0.0, sum = 0.0;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx)
      if (masked(pc.levelMask, W, H, x + dx, y + dy)) {
        n += 1.0;
        sum += pc.levelImage.v[(y + dy) * W + x + dx];
      }
  if (n < 13.0) return -1.0;
  precise float mean = sum / n;
  precise float squares = 0.0;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx)
      if (masked(pc.levelMask, W, H, x + dx, y + dy)) {
        precise float d = pc.levelImage.v[(y + dy) * W + x + dx] - mean;
        squares += d * d;
      }
  precise float variance = squares / n;
  return variance;
}

void main() {
  const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int W0 = pc.fullWidth, H0 = pc.fullHeight;
  float best[5] = float[5](0.0, 0.0, 0.0, 0.0, -1.0);
  const int X0 = blockStart(x, pc.width, W0), Y0 = blockStart(y, pc.height, H0);
  for (int Y = Y0; Y < H0 && coarseOf(Y, pc.height, H0) == y; ++Y)
    for (int X = X0; X < W0 && coarseOf(X, pc.width, W0) == x; ++X) {
      const float c = pc.confidence.v[Y * W0 + X];
      if (!masked(pc.mask, W0, H0, X, Y) || !(c > best[4])) continue;
      best = float[5](float(X), float(Y), pc.w.v[2 * (Y * W0 + X)], pc.w.v[2 * (Y * W0 + X) + 1], c);
    }
  const int i = 6 * (y * pc.width + x);
  for (int k = 0; k < 5; ++k) pc.support.v[i + k] = best[k];
  pc.support.v[i + 5] = windowVariance(x, y);
}

// Typed views onto the CPU backend's float buffers, bilinear sampling, and the
// row-parallel loop every CPU kernel uses.
#pragma once
#include <algorithm>
#include <cmath>
#include <functional>

namespace cs::cpu {

struct View {
  float* data;
  int width, height, channels;
  float& at(int x, int y, int c = 0) const { return data[(size_t(y) * width + x) * channels + c]; }
  bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
};

// Bilinear sample of channel c at (x, y), clamped to the image edge. Written out in
// arithmetic so every backend can reproduce it exactly.
inline float sampleBilinear(const View& v, float x, float y, int c = 0) {
  x = std::min(std::max(x, 0.f), float(v.width - 1));
  y = std::min(std::max(y, 0.f), float(v.height - 1));
  int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  int x1 = std::min(x0 + 1, v.width - 1), y1 = std::min(y0 + 1, v.height - 1);
  float fx = x - float(x0), fy = y - float(y0);
  float top = v.at(x0, y0, c) * (1.f - fx) + v.at(x1, y0, c) * fx;
  float bottom = v.at(x0, y1, c) * (1.f - fx) + v.at(x1, y1, c) * fx;
  return top * (1.f - fy) + bottom * fy;
}

// The estimate (u, w) of pixel (x, y) whose match moved by (wx, wy): w in float, u = |w|.
inline void storeWarp(const View& u, const View& w, double wx, double wy, int x, int y) {
  w.at(x, y, 0) = float(wx);
  w.at(x, y, 1) = float(wy);
  u.at(x, y) = float(std::sqrt(wx * wx + wy * wy));
}

inline bool masked(const View& mask, int x, int y) { return mask.inside(x, y) && mask.at(x, y) != 0.f; }

// Forward-difference links of the masked grid: the gradient across an image or mask
// border is zero (Neumann), and div is its exact negative adjoint.
inline bool linkX(const View& mask, int x, int y) { return masked(mask, x, y) && masked(mask, x + 1, y); }
inline bool linkY(const View& mask, int x, int y) { return masked(mask, x, y) && masked(mask, x, y + 1); }

// Runs body(y) for every row, split across hardware threads. Kernels write only their
// own rows, so results do not depend on the number of threads.
void parallelRows(int height, const std::function<void(int)>& body);

}  // namespace cs::cpu

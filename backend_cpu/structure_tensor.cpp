// The anisotropic diffusion tensor D = T^(1/2) of I0 and the diagonal preconditioner
// (Pock & Chambolle 2011, alpha = 1) of K(u, v) = (alpha1 (D grad u - v), alpha0 grad v)
// on the masked grid.
#include <cmath>
#include <vector>

#include "cpu_backend.hpp"

namespace cs::cpu {

namespace {

// Separable Gaussian blur with clamp-to-edge; sigma 0 copies.
std::vector<float> blur(const View& image, float sigma) {
  const int w = image.width, h = image.height;
  std::vector<float> out(size_t(w) * h);
  if (sigma <= 0.f) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) out[size_t(y) * w + x] = image.at(x, y);
    return out;
  }
  const std::vector<float> taps = gaussianTaps(sigma);
  const int radius = int(taps.size() / 2);
  std::vector<float> rows(out.size());
  parallelRows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      float s = 0.f;
      for (int i = -radius; i <= radius; ++i)
        s += taps[size_t(i + radius)] * image.at(std::min(std::max(x + i, 0), w - 1), y);
      rows[size_t(y) * w + x] = s;
    }
  });
  parallelRows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      float s = 0.f;
      for (int i = -radius; i <= radius; ++i)
        s += taps[size_t(i + radius)] * rows[size_t(std::min(std::max(y + i, 0), h - 1)) * w + x];
      out[size_t(y) * w + x] = s;
    }
  });
  return out;
}

struct Tensor {
  float d11, d12, d22;
};

Tensor tensorAt(const std::vector<float>& smooth, int w, int h, int x, int y, const TensorParams& p) {
  auto at = [&](int i, int j) {
    return smooth[size_t(std::min(std::max(j, 0), h - 1)) * w + std::min(std::max(i, 0), w - 1)];
  };
  float gx = 0.5f * (at(x + 1, y) - at(x - 1, y));
  float gy = 0.5f * (at(x, y + 1) - at(x, y - 1));
  float mag = std::sqrt(gx * gx + gy * gy);
  float weight = std::max(std::exp(-p.beta * std::pow(mag, p.eta)), p.wMin);
  // Without a gradient the tensor is the identity whatever n is (weight is 1).
  float nx = mag > 1e-12f ? gx / mag : 1.f, ny = mag > 1e-12f ? gy / mag : 0.f;
  return {weight * nx * nx + ny * ny, (weight - 1.f) * nx * ny, weight * ny * ny + nx * nx};
}

// Row sums of |K| for the two p rows of a pixel, u-part only (see primal_dual.cpp).
float rowSumP1(const View& t, bool ex, bool ey, int x, int y) {
  float d11 = ex ? t.at(x, y, 0) : 0.f, d12 = ey ? t.at(x, y, 1) : 0.f;
  return std::abs(d11 + d12) + std::abs(d11) + std::abs(d12);
}
float rowSumP2(const View& t, bool ex, bool ey, int x, int y) {
  float d12 = ex ? t.at(x, y, 1) : 0.f, d22 = ey ? t.at(x, y, 2) : 0.f;
  return std::abs(d12 + d22) + std::abs(d12) + std::abs(d22);
}

// Column sum of |K| for u(x, y): its own p rows plus the p rows of the left and upper
// neighbours whose forward differences reach it.
float columnSumU(const View& t, const View& mask, int x, int y) {
  bool ex = linkX(mask, x, y), ey = linkY(mask, x, y);
  float own = std::abs((ex ? t.at(x, y, 0) : 0.f) + (ey ? t.at(x, y, 1) : 0.f)) +
              std::abs((ex ? t.at(x, y, 1) : 0.f) + (ey ? t.at(x, y, 2) : 0.f));
  float left = linkX(mask, x - 1, y) ? std::abs(t.at(x - 1, y, 0)) + std::abs(t.at(x - 1, y, 1)) : 0.f;
  float up = linkY(mask, x, y - 1) ? std::abs(t.at(x, y - 1, 1)) + std::abs(t.at(x, y - 1, 2)) : 0.f;
  return own + left + up;
}

int gradientLinksTouching(const View& mask, int x, int y) {
  return int(linkX(mask, x, y)) + int(linkY(mask, x, y)) + int(linkX(mask, x - 1, y)) + int(linkY(mask, x, y - 1));
}

}  // namespace

void structureTensor(const View& tensor, const View& steps, const View& image, const View& mask,
                     const TensorParams& p) {
  const std::vector<float> smooth = blur(image, p.sigma);
  parallelRows(tensor.height, [&](int y) {
    for (int x = 0; x < tensor.width; ++x) {
      Tensor d = tensorAt(smooth, image.width, image.height, x, y, p);
      tensor.at(x, y, 0) = d.d11;
      tensor.at(x, y, 1) = d.d12;
      tensor.at(x, y, 2) = d.d22;
      tensor.at(x, y, 3) = 0.f;
    }
  });
  // A tiny floor keeps isolated pixels (no links) finite; their steps never matter.
  const float kFloor = 1e-2f;
  parallelRows(steps.height, [&](int y) {
    for (int x = 0; x < steps.width; ++x) {
      bool ex = linkX(mask, x, y), ey = linkY(mask, x, y);
      steps.at(x, y, 0) = 1.f / (p.alpha1 * std::max(columnSumU(tensor, mask, x, y), kFloor));
      steps.at(x, y, 1) = 1.f / (p.alpha1 + p.alpha0 * float(gradientLinksTouching(mask, x, y)));
      steps.at(x, y, 2) = 1.f / (p.alpha1 * (rowSumP1(tensor, ex, ey, x, y) + 1.f));
      steps.at(x, y, 3) = 1.f / (p.alpha1 * (rowSumP2(tensor, ex, ey, x, y) + 1.f));
    }
  });
}

}  // namespace cs::cpu

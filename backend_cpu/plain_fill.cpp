// Plain regions (backend.hpp plainSupport, fillPlanes): the most confident full-resolution
// pixel under each coarse pixel, for the host's plane fits (core/src/plain_fill.cpp), and
// the planes it found written back into level 0's estimate.
#include <algorithm>
#include <cmath>

#include "cpu_backend.hpp"
#include "curvestereo/camera.hpp"

namespace cs::cpu {

namespace {

// The coarse pixel a full-resolution one falls in (backend.hpp): integer arithmetic, the
// same on every backend.
int coarseOf(int X, int coarse, int full) { return int(((2LL * X + 1) * coarse) / (2LL * full)); }

// The first full-resolution index whose coarse pixel is c (coarseOf is monotonic).
int blockStart(int c, int coarse, int full) {
  int X = std::max(0, int((long long)c * full / coarse) - 1);
  while (X < full && coarseOf(X, coarse, full) < c) ++X;
  return X;
}

// The variance of the level image over the 5 x 5 window's masked pixels (-1: the pixel
// unmasked or the window mostly outside): the host tells plain from textured by it.
float windowVariance(const View& image, const View& mask, int x, int y) {
  constexpr int r = 2;
  if (!masked(mask, x, y)) return -1.f;
  float n = 0.f, sum = 0.f;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx)
      if (masked(mask, x + dx, y + dy)) n += 1.f, sum += image.at(x + dx, y + dy);
  if (n < 13.f) return -1.f;
  const float mean = sum / n;
  float squares = 0.f;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx)
      if (masked(mask, x + dx, y + dy)) {
        const float d = image.at(x + dx, y + dy) - mean;
        squares += d * d;
      }
  return squares / n;
}

}  // namespace

void plainSupport(const View& support, const View& confidence, const View& w, const View& mask, const View& levelImage,
                  const View& levelMask) {
  parallelRows(support.height, [&](int y) {
    const int Y0 = blockStart(y, support.height, mask.height);
    for (int x = 0; x < support.width; ++x) {
      float best[5] = {0.f, 0.f, 0.f, 0.f, -1.f};
      const int X0 = blockStart(x, support.width, mask.width);
      for (int Y = Y0; Y < mask.height && coarseOf(Y, support.height, mask.height) == y; ++Y)
        for (int X = X0; X < mask.width && coarseOf(X, support.width, mask.width) == x; ++X) {
          const float c = confidence.at(X, Y);
          if (!masked(mask, X, Y) || !(c > best[4])) continue;
          best[0] = float(X), best[1] = float(Y), best[2] = w.at(X, Y, 0), best[3] = w.at(X, Y, 1), best[4] = c;
        }
      for (int k = 0; k < 5; ++k) support.at(x, y, k) = best[k];
      support.at(x, y, 5) = windowVariance(levelImage, levelMask, x, y);
    }
  });
}

void fillPlanes(const View& u, const View& w, const View& planeConfidence, const View& labels, const View& planes,
                const View& mask, const CameraParams& cam0p, const double tPrime[3]) {
  const BuiltCamera cam(toCamera(cam0p));
  const long long planeCount = (long long)planes.width * planes.height / 3;
  parallelRows(u.height, [&](int y) {
    const int ly = coarseOf(y, labels.height, u.height);
    for (int x = 0; x < u.width; ++x) {
      planeConfidence.at(x, y) = 0.f;
      if (!masked(mask, x, y)) continue;
      const int lx = coarseOf(x, labels.width, u.width);
      const float label = labels.at(lx, ly, 0);
      if (!(label >= 0.f) || (long long)label >= planeCount) continue;
      const int i = 3 * int(label);
      Vec3<double> ray;
      if (!cam.unproject(Vec2<double>(x, y), ray)) continue;
      const double q = double(planes.data[i]) * ray.x() + double(planes.data[i + 1]) * ray.y() +
                       double(planes.data[i + 2]) * ray.z();
      Vec2<double> px;
      if (!(q >= 0.0) ||
          !cam.project(Vec3<double>(ray.x() + q * tPrime[0], ray.y() + q * tPrime[1], ray.z() + q * tPrime[2]), px))
        continue;
      storeWarp(u, w, px.x() - x, px.y() - y, x, y);
      planeConfidence.at(x, y) = labels.at(lx, ly, 1);
    }
  });
}

}  // namespace cs::cpu

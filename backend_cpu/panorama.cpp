// A rig's panorama (backend.hpp panoramaPlace, panoramaSplat, panoramaResolve): each
// camera pixel placed as a footprint in the equirectangular panorama, splatted in three
// passes (best confidence, the nearest surface among the confident, the mean over that
// surface), then resolved. All in float, as the GPU backends do it.
#include <algorithm>
#include <cmath>
#include <limits>

#include "cpu_backend.hpp"
#include "curvestereo/parallel.hpp"

namespace cs::cpu {

namespace {

constexpr float kPi = 3.14159265358979323846f;

// Two inverse ranges on one surface (backend.hpp): within a share of the larger, or within
// the parallax the solves cannot resolve (far points: the share alone would split one
// distant wall's noisy estimates and keep the nearest).
bool sameSurface(float inverseA, float inverseB, const PanoramaParams& p) {
  return std::fabs(inverseA - inverseB) <= kPanoramaAgreement * std::max(inverseA, inverseB) + p.parallaxSlack;
}

bool rayAt(const View& rays, int x, int y, float d[3]) {
  for (int k = 0; k < 3; ++k) d[k] = rays.at(x, y, k);
  return std::isfinite(d[0]) && std::isfinite(d[1]) && std::isfinite(d[2]);
}

// Pixel (x, y)'s column and row in the panorama and its range from the centre; false where
// it has no estimate or no ray.
bool placePixel(const View& radial, const View& rays, int x, int y, const PanoramaParams& p, float& column, float& row,
                float& range) {
  const float r = radial.at(x, y);
  float d[3];
  if (std::isnan(r) || !rayAt(rays, x, y, d)) return false;
  const bool finite = std::isfinite(r);
  const float px = finite ? r * d[0] + p.centre[0] : d[0], py = finite ? r * d[1] + p.centre[1] : d[1],
              pz = finite ? r * d[2] + p.centre[2] : d[2];
  const float lon = std::atan2(px, pz), lat = std::atan2(-py, std::sqrt(px * px + pz * pz));
  const float width = float(p.width), height = float(p.width / 2);
  column = (lon + kPi) / (2.f * kPi) * width - 0.5f;
  row = (kPi / 2.f - lat) / kPi * height - 0.5f;
  range = finite ? std::sqrt(px * px + py * py + pz * pz) : std::numeric_limits<float>::infinity();
  return true;
}

// The footprint's half-sizes: half the spacing to the neighbours on the same surface (a box
// of half-size (|a| + |b|) / 2 covers the cell they span however the camera's grid lies in
// the panorama, so it has no holes where it samples more finely than the camera), at least
// half a pixel, at most kPanoramaMaxSplat of arc: a column's arc shrinks with cos(latitude).
void footprint(const View& radial, const View& rays, int x, int y, float column, float row, const PanoramaParams& p,
               float& hx, float& hy) {
  const float width = float(p.width), height = float(p.width / 2), inverse = 1.f / radial.at(x, y);
  float a[2] = {0.f, 0.f}, b[2] = {0.f, 0.f};
  const int nx[4] = {x + 1, x, x - 1, x}, ny[4] = {y, y + 1, y, y - 1};
  for (int k = 0; k < 4; ++k) {
    if (!radial.inside(nx[k], ny[k])) continue;
    const float rn = radial.at(nx[k], ny[k]);
    float c, r, range;
    if (std::isnan(rn) || !sameSurface(1.f / rn, inverse, p) || !placePixel(radial, rays, nx[k], ny[k], p, c, r, range))
      continue;
    float step[2] = {c - column, r - row};
    if (std::fabs(step[0]) > 0.5f * width) step[0] = std::remainder(step[0], width);  // across the seam
    float* along = ny[k] == y ? a : b;
    for (int i = 0; i < 2; ++i) along[i] = std::max(along[i], std::fabs(step[i]));
  }
  const float latitude = kPi / 2.f - kPi * (row + 0.5f) / height;
  const float columns = kPanoramaMaxSplat / std::max(std::cos(latitude), 2.f * kPanoramaMaxSplat / width);
  hx = std::clamp(0.5f * (a[0] + b[0]), 0.5f, columns);  // columns >= kPanoramaMaxSplat
  hy = std::clamp(0.5f * (a[1] + b[1]), 0.5f, kPanoramaMaxSplat);
}

// One splat's contribution to panorama pixel k (6 channels at acc).
void splatInto(float* acc, const PanoramaParams& p, float confidence, float weight, float inverse, float grey) {
  switch (p.pass) {
    case kPanoramaBest:
      acc[0] = std::max(acc[0], confidence);
      break;
    case kPanoramaNearest:
      if (confidence >= 0.5f * acc[0]) acc[1] = std::max(acc[1], inverse);
      break;
    default:
      if (!(confidence >= 0.5f * acc[0]) || !sameSurface(inverse, acc[1], p)) break;
      acc[2] += weight * inverse;
      acc[3] += weight;
      if (std::isfinite(grey)) acc[4] += weight * grey, acc[5] += weight;
  }
}

}  // namespace

void panoramaPlace(const View& place, const View& radial, const View& rays, const PanoramaParams& p) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  parallelRows(radial.height, [&](int y) {
    for (int x = 0; x < radial.width; ++x) {
      float column, row, range, hx, hy;
      for (int c = 0; c < kPanoramaPlaceChannels; ++c) place.at(x, y, c) = nan;
      if (!placePixel(radial, rays, x, y, p, column, row, range)) continue;
      footprint(radial, rays, x, y, column, row, p, hx, hy);
      const float values[kPanoramaPlaceChannels] = {column, row, hx, hy, range};
      for (int c = 0; c < kPanoramaPlaceChannels; ++c) place.at(x, y, c) = values[c];
    }
  });
}

// The panorama's rows in one band per worker, each band's thread taking the camera's pixels
// in order: a panorama pixel receives its samples in that order whatever the number of
// bands, so the result does not depend on the thread count.
void panoramaSplat(const View& accum, const View& place, const View& confidence, const View* grey,
                   const PanoramaParams& p) {
  const int width = p.width, height = p.width / 2, bands = std::clamp(detail::parallelWorkers(), 1, height);
  detail::parallelFor(
      bands,
      [&](int band) {
        const int first = int(1LL * height * band / bands), last = int(1LL * height * (band + 1) / bands) - 1;
        for (int cy = 0; cy < place.height; ++cy)
          for (int cx = 0; cx < place.width; ++cx) {
            const float column = place.at(cx, cy, 0), row = place.at(cx, cy, 1), hy = place.at(cx, cy, 3);
            if (std::isnan(column)) continue;
            const int y0 = std::max({0, first, int(std::ceil(row - hy))});
            const int y1 = std::min({height - 1, last, int(std::floor(row + hy))});
            const float c0 = confidence.at(cx, cy);
            if (y0 > y1 || (p.minConfidence > 0.f && !(c0 >= p.minConfidence))) continue;
            const float c = std::isfinite(c0) ? c0 : 0.f, weight = std::isfinite(c0) ? std::max(c0, 1e-6f) : 1e-6f;
            const float inverse = 1.f / place.at(cx, cy, 4), g = grey ? grey->at(cx, cy) : std::nanf("");
            const float hx = place.at(cx, cy, 2);
            const int x0 = int(std::ceil(column - hx)), x1 = int(std::floor(column + hx));
            for (int y = y0; y <= y1; ++y)
              for (int x = x0, wrapped = ((x0 % width) + width) % width; x <= x1;
                   ++x, wrapped = wrapped + 1 == width ? 0 : wrapped + 1)
                splatInto(&accum.at(wrapped, y), p, c, weight, inverse, g);
          }
      },
      1);
}

void panoramaResolve(const View& range, const View& grey, const View& confidence, const View& accum) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  parallelRows(accum.height, [&](int y) {
    for (int x = 0; x < accum.width; ++x) {
      float* acc = &accum.at(x, y);
      range.at(x, y) = grey.at(x, y) = confidence.at(x, y) = nan;
      if (acc[3] > 0.f) {
        range.at(x, y) = acc[3] / acc[2];
        confidence.at(x, y) = acc[0];
        if (acc[5] > 0.f) grey.at(x, y) = acc[4] / acc[5];
      }
      std::fill(acc, acc + kPanoramaChannels, 0.f);
    }
  });
}

}  // namespace cs::cpu

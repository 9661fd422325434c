// Golden cases of a rig's panorama kernels (backend.hpp panoramaPlace, panoramaSplat,
// panoramaResolve).
#include <cmath>
#include <limits>

#include "golden_inputs.hpp"

namespace cs::golden {

namespace {

constexpr int kPanoramaWidth = 48;

// Unit rays of an equidistant fisheye of 200 degrees looking along -z (so that the
// panorama's seam, longitude +-pi, crosses the middle of the image), NaN outside its circle.
Host backwardRays() {
  Host rays(kW, kH, 3);
  const float cx = 0.5f * float(kW - 1), cy = 0.5f * float(kH - 1),
              f = 0.5f * float(kH) / (100.f * 3.14159265f / 180.f);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const float dx = float(x) - cx, dy = float(y) - cy, r = std::hypot(dx, dy), theta = r / f;
      const bool inside = theta <= 100.f * 3.14159265f / 180.f;
      const float s = r > 0.f ? std::sin(theta) / r : 0.f;
      const float d[3] = {-s * dx, s * dy, -std::cos(theta)};  // x mirrored: looking backwards
      for (int k = 0; k < 3; ++k) rays.at(x, y, k) = inside ? d[k] : std::numeric_limits<float>::quiet_NaN();
    }
  return rays;
}

// Ranges of a slanted wall with a nearer box in front, some pixels at infinity (the sky) and
// some with no estimate.
Host wallAndBox() {
  Host radial(kW, kH, 1);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      float r = 3.f + 0.05f * float(x) + 0.02f * float(y);
      if (x > 15 && x < 26 && y > 10 && y < 22) r = 1.2f + 0.01f * float(x);
      if (y < 4) r = std::numeric_limits<float>::infinity();
      if ((x * 5 + y * 3) % 23 == 0) r = std::numeric_limits<float>::quiet_NaN();
      radial.at(x, y) = r;
    }
  return radial;
}

}  // namespace

std::vector<Output> panoramaPlaceCase(Backend& b) {
  Session s{b};
  Host rays = backwardRays(), radial = wallAndBox();
  // A parallax slack that joins some of the sky's rows (inverse range 0) to the wall's
  // (0.18 to 0.32), so that both sides of the test are taken.
  PanoramaParams p{kPanoramaWidth, {0.08f, -0.03f, 0.05f}, 0.f, kPanoramaBest, 0.25f};
  Buffer place = s.make(kW, kH, kPanoramaPlaceChannels);
  b.panoramaPlace(place, s.put(radial), s.put(rays), p);
  // atan2, cos and sqrt of the device: a few ulps of positions up to 48 px.
  return within({s.get("panorama_place", place)}, {1e-4, 1e-11});
}

// Two cameras' footprints placed at random (seams, the top and bottom rows, overlaps at
// several ranges, +inf, NaN confidences and greys, one camera gated by a confidence, and
// some boxes near the top pole over 32 pixels wide and up to the whole width), each
// pass over both before the next; the accumulator, what it resolves to, and the accumulator
// left cleared for the next frame.
std::vector<Output> panoramaSplatCase(Backend& b) {
  Session s{b};
  const int cw = 21, ch = 15, height = kPanoramaWidth / 2;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  Buffer accum = s.make(kPanoramaWidth, height, kPanoramaChannels);
  std::vector<Buffer> places, confidences, greys;
  for (uint32_t camera = 0; camera < 2; ++camera) {
    Host place(cw, ch, kPanoramaPlaceChannels), confidence(cw, ch, 1), grey(cw, ch, 1);
    for (int y = 0; y < ch; ++y)
      for (int x = 0; x < cw; ++x) {
        const uint32_t i = uint32_t(y * cw + x) * 7u + camera * 1000u;
        const float values[kPanoramaPlaceChannels] = {hash01(i) * kPanoramaWidth - 0.5f, hash01(i + 1) * height - 0.5f,
                                                      0.5f + 2.5f * hash01(i + 2), 0.5f + 1.5f * hash01(i + 3),
                                                      (i % 11 == 0) ? inf : 1.f + 3.f * hash01(i + 4)};
        for (int k = 0; k < kPanoramaPlaceChannels; ++k) place.at(x, y, k) = values[k];
        if ((x + 2 * y) % 23 == 0) {  // near a pole: tens of columns (GPUs share such a box out)
          place.at(x, y, 1) = 0.5f + 2.f * hash01(i + 7);
          place.at(x, y, 2) = 8.f + 16.f * hash01(i + 8);
          place.at(x, y, 3) = 1.5f;
        }
        if (i % 13 == 0) place.at(x, y, 0) = nan;
        confidence.at(x, y) = i % 17 == 0 ? nan : hash01(i + 5);
        grey.at(x, y) = i % 19 == 0 ? nan : hash01(i + 6);
      }
    places.push_back(s.put(place)), confidences.push_back(s.put(confidence)), greys.push_back(s.put(grey));
  }
  const Buffer none{};
  for (int pass = kPanoramaBest; pass <= kPanoramaSums; ++pass)
    for (size_t camera = 0; camera < 2; ++camera) {
      // A slack of a tenth of the ranges' inverse span (0.25 to 1): some samples off the
      // nearest surface by its share join it.
      const PanoramaParams p{kPanoramaWidth, {0.f, 0.f, 0.f}, camera == 1 ? 0.3f : 0.f, pass, 0.08f};
      b.panoramaSplat(accum, places[camera], confidences[camera], camera == 0 ? greys[camera] : none, p);
    }
  Output splatted = s.get("panorama_accum", accum);
  Buffer range = s.make(kPanoramaWidth, height, 1), grey = s.make(kPanoramaWidth, height, 1),
         confidence = s.make(kPanoramaWidth, height, 1);
  b.panoramaResolve(range, grey, confidence, accum);
  std::vector<Output> out = {splatted, s.get("panorama_range", range), s.get("panorama_grey", grey),
                             s.get("panorama_confidence", confidence), s.get("panorama_cleared", accum)};
  // Sums of a few dozen terms of order 1 in the device's order (atomics): a few ulps.
  return within(out, {1e-4, 1e-11});
}

}  // namespace cs::golden

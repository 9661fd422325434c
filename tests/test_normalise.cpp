// Local contrast normalisation (Backend::normalise, backend_cpu/normalise.cpp): the
// oracle against the contract computed directly in double (a 2-D window, not two passes),
// invariance to gain and offset, zero mean and unit variance of the output on random
// texture, 0 outside the mask, 0 on a flat image.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "cpu_backend.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/pipeline_params.hpp"
#include "golden_cases.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

struct Plane {
  int w, h, c;
  std::vector<float> v;
  Plane(int w_, int h_, int c_ = 1, float value = 0.f) : w(w_), h(h_), c(c_), v(size_t(w_) * h_ * c_, value) {}
  float& at(int x, int y, int ch = 0) { return v[(size_t(y) * w + x) * c + ch]; }
  float at(int x, int y, int ch = 0) const { return v[(size_t(y) * w + x) * c + ch]; }
  cpu::View view() { return cpu::View{v.data(), w, h, c}; }
};

// White noise in [0, 1], or smoothed by `passes` 3x3 box passes (values stay in [0, 1]).
Plane texture(int w, int h, uint32_t seed, int passes) {
  Plane t(w, h);
  for (size_t i = 0; i < t.v.size(); ++i) t.v[i] = golden::hash01(uint32_t(i) * 747796405U + seed);
  for (int pass = 0; pass < passes; ++pass) {
    const Plane s = t;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        float sum = 0.f;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx)
            sum += s.v[size_t(std::clamp(y + dy, 0, h - 1)) * w + size_t(std::clamp(x + dx, 0, w - 1))];
        t.at(x, y) = sum / 9.f;
      }
  }
  return t;
}

// A disc of radius `radius` about the centre, with a 3x3 hole near it.
Plane disc(int w, int h, double radius) {
  Plane m(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) m.at(x, y) = std::hypot(x - 0.5 * (w - 1), y - 0.5 * (h - 1)) <= radius ? 1.f : 0.f;
  for (int y = h / 2 + 4; y < h / 2 + 7; ++y)
    for (int x = w / 2 - 5; x < w / 2 - 2; ++x) m.at(x, y) = 0.f;
  return m;
}

NormaliseParams taps(float sigma, float epsilon) {
  Params p;
  p.normSigma = sigma;
  NormaliseParams n = normaliseParams(p);
  n.epsilon = epsilon;
  return n;
}

Plane normalised(Plane src, Plane mask, const NormaliseParams& p) {
  Plane dst(src.w, src.h, 1, -7.f), moments(src.w, src.h, 3, -7.f);
  cpu::normalise(dst.view(), moments.view(), src.view(), mask.view(), p);
  return dst;
}

}  // namespace

TEST_CASE("normalise: the oracle computes the contract's masked 2-D window mean and variance") {
  const int w = 53, h = 41;
  Plane src = texture(w, h, 3, 1), mask = disc(w, h, 17.0);
  const NormaliseParams p = taps(2.5f, 0.01f);
  REQUIRE(p.radius == 8);
  Plane dst = normalised(src, mask, p);
  double worst = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (mask.at(x, y) == 0.f) continue;
      double s0 = 0, s1 = 0, s2 = 0;
      for (int j = -p.radius; j <= p.radius; ++j)
        for (int i = -p.radius; i <= p.radius; ++i) {
          const int sx = x + i, sy = y + j;
          if (sx < 0 || sy < 0 || sx >= w || sy >= h || mask.at(sx, sy) == 0.f) continue;
          const double t = double(p.taps[i + p.radius]) * p.taps[j + p.radius], v = src.at(sx, sy);
          s0 += t, s1 += t * v, s2 += t * v * v;
        }
      const double mean = s1 / s0, variance = std::max(0.0, s2 / s0 - mean * mean);
      const double expected = (src.at(x, y) - mean) / std::sqrt(variance + double(p.epsilon) * p.epsilon);
      worst = std::max(worst, std::abs(expected - dst.at(x, y)));
    }
  MESSAGE("max abs difference from the double 2-D evaluation: " << worst);
  CHECK(worst < 1e-3);
}

TEST_CASE("normalise: invariant to a gain and an offset (up to epsilon), 0 outside the mask") {
  const int w = 61, h = 47;
  const Plane src = texture(w, h, 7, 1), mask = disc(w, h, 21.0);
  const NormaliseParams p = taps(2.5f, 1e-6f);
  const Plane ref = normalised(src, mask, p);
  double largest = 0;
  for (float v : ref.v) largest = std::max(largest, double(std::abs(v)));
  CHECK(largest > 1.0);  // not trivially zero
  // Grey levels of a plausible range. The variance is E[I^2] - E[I]^2 in float, which loses
  // about log2(mean^2 / variance) bits: an offset far above the contrast (gain 1, offset 5
  // here: mean^2 / variance ~ 3000) moves the output by 2e-3, gain 0.2 offset 0.7 by 9e-4.
  for (auto [gain, offset] : {std::pair{2.5f, 0.3f}, std::pair{0.4f, -0.2f}, std::pair{0.5f, 0.4f}}) {
    INFO("gain " << gain << ", offset " << offset);
    Plane scaled = src;
    for (float& v : scaled.v) v = gain * v + offset;
    const Plane out = normalised(scaled, mask, p);
    double worst = 0;
    long long outside = 0, outsideNonZero = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        if (mask.at(x, y) == 0.f) {
          ++outside;
          outsideNonZero += out.at(x, y) != 0.f;
        } else {
          worst = std::max(worst, double(std::abs(out.at(x, y) - ref.at(x, y))));
        }
      }
    MESSAGE("gain " << gain << ", offset " << offset << ": max abs change " << worst);
    CHECK(worst < 1e-3);
    CHECK(outside > 9);  // the corners and the hole
    CHECK(outsideNonZero == 0);
  }
}

TEST_CASE("normalise: zero mean and unit variance on random texture inside a large masked region") {
  const int w = 161, h = 149;
  const Plane src = texture(w, h, 11, 0), mask = disc(w, h, 70.0);
  const NormaliseParams p = taps(4.f, 1e-6f);
  const Plane dst = normalised(src, mask, p);
  // Over the pixels whose whole window lies inside the mask (the rim's windows are cut).
  double n = 0, sum = 0, squares = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (std::hypot(x - 0.5 * (w - 1), y - 0.5 * (h - 1)) > 70.0 - 1.5 * p.radius) continue;
      n += 1, sum += dst.at(x, y), squares += double(dst.at(x, y)) * dst.at(x, y);
    }
  const double mean = sum / n, variance = squares / n - mean * mean;
  MESSAGE(n << " pixels: mean " << mean << ", variance " << variance);
  REQUIRE(n > 5000);
  CHECK(std::abs(mean) < 0.03);
  // A local estimate is a little off the texture's own: E[(I - m)^2] / E[s^2] is
  // (1 - 2 w0 + sum w^2) / (1 - sum w^2) ~ 0.99 for sigma 4 (w0 the centre's weight).
  CHECK(variance > 0.95);
  CHECK(variance < 1.05);
}

TEST_CASE("normalise: a flat image gives 0 everywhere") {
  const int w = 37, h = 29;
  const Plane mask = disc(w, h, 12.0);
  for (float value : {0.f, 0.37f, 1.f}) {
    const Plane dst = normalised(Plane(w, h, 1, value), mask, taps(2.5f, 0.01f));
    double worst = 0;
    for (float v : dst.v) worst = std::max(worst, double(std::abs(v)));
    INFO("value " << value);
    CHECK(worst < 1e-4);  // the mean's rounding (a few ulp of the grey level) over epsilon
  }
}

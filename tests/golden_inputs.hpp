// What the golden cases are made of (golden_cases.cpp, golden_cases_result.cpp): the golden
// size, deterministic host images, a session that uploads them and reads outputs back, and
// the cases that live in golden_cases_result.cpp. Internal to the tests.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "cpu_views.hpp"
#include "curvestereo/camera.hpp"
#include "golden_cases.hpp"

namespace cs::golden {

// Odd sizes on purpose: no kernel may assume even or aligned dimensions.
constexpr int kW = 45, kH = 37;

inline float hashNoise(uint32_t i) { return hash01(i); }

// Interleaved host data for one buffer.
struct Host {
  int w, h, c;
  std::vector<float> v;
  Host(int w_, int h_, int c_) : w(w_), h(h_), c(c_), v(size_t(w_) * h_ * c_, 0.f) {}
  float& at(int x, int y, int ch = 0) { return v[(size_t(y) * w + x) * c + ch]; }
  cpu::View view() { return cpu::View{v.data(), w, h, c}; }
};

// Smooth random texture in [0, 1]: hash noise blurred by `passes` 3x3 box passes.
inline Host texture(int w, int h, uint32_t seed, int passes = 3) {
  Host t(w, h, 1);
  for (size_t i = 0; i < t.v.size(); ++i) t.v[i] = hashNoise(uint32_t(i) * 747796405U + seed);
  for (int pass = 0; pass < passes; ++pass) {
    Host s = t;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        float sum = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) sum += s.at(std::clamp(x + dx, 0, w - 1), std::clamp(y + dy, 0, h - 1));
        t.at(x, y) = sum / 9.f;
      }
  }
  return t;
}

// Values in [-amp, amp] per channel, no smoothing.
inline Host noise(int w, int h, int c, uint32_t seed, float amp) {
  Host n(w, h, c);
  for (size_t i = 0; i < n.v.size(); ++i) n.v[i] = amp * (2.f * hashNoise(uint32_t(i) * 2891336453U + seed) - 1.f);
  return n;
}

// A disc filling most of the image, with a small hole, like a fisheye image circle.
inline Host discMask(int w, int h) {
  Host m(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) m.at(x, y) = std::hypot(x - 0.5 * (w - 1), y - 0.5 * (h - 1)) <= 0.45 * std::min(w, h);
  m.at(w / 2, h / 2) = 0.f;
  return m;
}

// A smoothly turning unit vector field (a stand-in for an epipolar tangent field).
inline Host tangentField(int w, int h) {
  Host t(w, h, 2);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float a = 0.4f + 0.03f * x - 0.02f * y;
      t.at(x, y, 0) = std::cos(a);
      t.at(x, y, 1) = std::sin(a);
    }
  return t;
}

struct Session {
  Backend& b;
  Buffer put(Host& h) {
    Buffer buf = b.create(h.w, h.h, h.c);
    b.upload(buf, h.v.data());
    return buf;
  }
  Buffer make(int w, int h, int c) {
    Buffer buf = b.create(w, h, c);
    b.fill(buf, 0.f);
    return buf;
  }
  Output get(const std::string& name, const Buffer& buf) {
    std::vector<float> data(buf.count());
    b.download(buf, data.data());
    Output o{name, ImageF(buf.width, buf.height * buf.channels), Tolerance{}};
    for (int c = 0; c < buf.channels; ++c)
      for (int y = 0; y < buf.height; ++y)
        for (int x = 0; x < buf.width; ++x)
          o.planes(x, c * buf.height + y) = data[(size_t(y) * buf.width + x) * buf.channels + c];
    return o;
  }
};

const TensorParams kTensor{9.f, 0.85f, 1e-4f, 1.f, 17.f, 1.2f};

// A T265-like Kannala-Brandt lens at the odd golden size, and a pose with rotation.
inline FieldsParams fieldsParams() {
  FieldsParams p{};
  p.cam0 = toCameraParams(Camera::kannalaBrandt4(kW, kH, 15.2, 15.3, 22.4, 18.1, -0.0066, 0.0473, -0.0458, 0.009));
  p.cam1 = toCameraParams(Camera::kannalaBrandt4(kW, kH, 15.1, 15.2, 22.8, 17.9, -0.005, 0.039, -0.035, 0.005));
  // 7 degrees: a crescent of camera 0 lies beyond camera 1's field of view.
  const double c = std::cos(0.12), sn = std::sin(0.12);
  const double R[9] = {c, 0, sn, 0, 1, 0, -sn, 0, c};
  std::copy(R, R + 9, p.R);
  p.t[0] = -0.064, p.t[1] = 0.001, p.t[2] = 0.002;
  p.maxFovDeg = 120;  // inside the disc mask, so that both cameras' limits show
  p.epipoleDeg = 3;
  return p;
}

// golden_cases_result.cpp: sequences and the result's confidence.
std::vector<Output> carryEstimateCase(Backend& b);
std::vector<Output> carryEstimateCoarseCase(Backend& b);
std::vector<Output> temporalFilterCase(Backend& b);
std::vector<Output> plainSupportCase(Backend& b);
std::vector<Output> fillPlanesCase(Backend& b);
std::vector<Output> roundTripCase(Backend& b);
std::vector<Output> resultConfidenceCase(Backend& b);
std::vector<Output> resultConfidenceAloneCase(Backend& b);
std::vector<Output> finishResultCase(Backend& b);

// golden_cases_panorama.cpp: a rig's panorama.
std::vector<Output> panoramaPlaceCase(Backend& b);
std::vector<Output> panoramaSplatCase(Backend& b);

}  // namespace cs::golden

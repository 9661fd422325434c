#include "golden_cases.hpp"

#include <cmath>
#include <filesystem>

#include "cpu_backend.hpp"
#include "curvestereo/camera.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/stereo.hpp"
#include "synth/scene.hpp"

namespace cs::golden {

namespace {

// Odd sizes on purpose: no kernel may assume even or aligned dimensions.
constexpr int kW = 45, kH = 37;

float hashNoise(uint32_t i) { return hash01(i); }

// Interleaved host data for one buffer.
struct Host {
  int w, h, c;
  std::vector<float> v;
  Host(int w_, int h_, int c_) : w(w_), h(h_), c(c_), v(size_t(w_) * h_ * c_, 0.f) {}
  float& at(int x, int y, int ch = 0) { return v[(size_t(y) * w + x) * c + ch]; }
  cpu::View view() { return cpu::View{v.data(), w, h, c}; }
};

// Smooth random texture in [0, 1]: hash noise blurred by three 3x3 box passes.
Host texture(int w, int h, uint32_t seed) {
  Host t(w, h, 1);
  for (size_t i = 0; i < t.v.size(); ++i) t.v[i] = hashNoise(uint32_t(i) * 747796405U + seed);
  for (int pass = 0; pass < 3; ++pass) {
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
Host noise(int w, int h, int c, uint32_t seed, float amp) {
  Host n(w, h, c);
  for (size_t i = 0; i < n.v.size(); ++i) n.v[i] = amp * (2.f * hashNoise(uint32_t(i) * 2891336453U + seed) - 1.f);
  return n;
}

// A disc filling most of the image, with a small hole, like a fisheye image circle.
Host discMask(int w, int h) {
  Host m(w, h, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) m.at(x, y) = std::hypot(x - 0.5 * (w - 1), y - 0.5 * (h - 1)) <= 0.45 * std::min(w, h);
  m.at(w / 2, h / 2) = 0.f;
  return m;
}

// A smoothly turning unit vector field (a stand-in for an epipolar tangent field).
Host tangentField(int w, int h) {
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
    Output o{name, ImageF(buf.width, buf.height * buf.channels)};
    for (int c = 0; c < buf.channels; ++c)
      for (int y = 0; y < buf.height; ++y)
        for (int x = 0; x < buf.width; ++x)
          o.planes(x, c * buf.height + y) = data[(size_t(y) * buf.width + x) * buf.channels + c];
    return o;
  }
};

const TensorParams kTensor{9.f, 0.85f, 1e-4f, 1.f, 17.f, 1.2f};

std::vector<Output> warpCase(Backend& b) {
  Session s{b};
  Host src = texture(kW, kH, 1), flow = noise(kW, kH, 2, 2, 3.f);
  Buffer dst = s.make(kW, kH, 1);
  b.warp(dst, s.put(src), s.put(flow));
  return {s.get("warp_dst", dst)};
}

std::vector<Output> downsampleCase(Backend& b) {
  Session s{b};
  Host src = texture(kW, kH, 3);
  Buffer dst = s.make((kW + 1) / 2, (kH + 1) / 2, 1);
  b.downsample(dst, s.put(src), 2.f);
  return {s.get("downsample_dst", dst)};
}

std::vector<Output> upsampleCase(Backend& b) {
  Session s{b};
  Host src = noise((kW + 1) / 2, (kH + 1) / 2, 2, 4, 1.f);
  Buffer dst = s.make(kW, kH, 2);
  b.upsample(dst, s.put(src), 2.f, 2.f);
  return {s.get("upsample_dst", dst)};
}

std::vector<Output> structureTensorCase(Backend& b) {
  Session s{b};
  Host image = texture(kW, kH, 5), mask = discMask(kW, kH);
  Buffer tensor = s.make(kW, kH, 4), steps = s.make(kW, kH, 4);
  b.structureTensor(tensor, steps, s.put(image), s.put(mask), kTensor);
  return {s.get("tensor_tensor", tensor), s.get("tensor_steps", steps)};
}

std::vector<Output> warpDerivativesCase(Backend& b) {
  Session s{b};
  Host i0 = texture(kW, kH, 6), i1 = texture(kW, kH, 7), traj = tangentField(kW, kH), w = noise(kW, kH, 2, 8, 2.f),
       u = noise(kW, kH, 1, 9, 2.f), mask = discMask(kW, kH);
  DataTermBuffers data{s.make(kW, kH, 1), s.make(kW, kH, 1), s.make(kW, kH, 1)};
  Buffer tangent = s.make(kW, kH, 2);
  b.warpDerivatives(data, tangent, s.put(i0), s.put(i1), s.put(traj), s.put(w), s.put(u), s.put(mask));
  return {s.get("derivatives_u0", data.u0), s.get("derivatives_iu", data.iu), s.get("derivatives_iz", data.iz),
          s.get("derivatives_tangent", tangent)};
}

std::vector<Output> primalDualCase(Backend& b) {
  Session s{b};
  Host image = texture(kW, kH, 10), mask = discMask(kW, kH), tensor(kW, kH, 4), steps(kW, kH, 4);
  // The preconditioner comes from the oracle so that this case tests primalDual alone.
  cpu::structureTensor(tensor.view(), steps.view(), image.view(), mask.view(), kTensor);
  Host u = noise(kW, kH, 1, 11, 1.f), v = noise(kW, kH, 2, 12, 0.1f), p = noise(kW, kH, 2, 13, 0.5f),
       q = noise(kW, kH, 4, 14, 0.2f), u0 = noise(kW, kH, 1, 15, 1.f), iu = noise(kW, kH, 1, 16, 0.1f),
       iz = noise(kW, kH, 1, 17, 0.05f);
  PrimalDualBuffers pd{s.put(u), s.put(u), s.put(v), s.put(v), s.put(p), s.put(q)};
  DataTermBuffers data{s.put(u0), s.put(iu), s.put(iz)};
  PrimalDualParams prm{20.f, 17.f, 1.2f, {}};
  float scale = 1.f;
  for (int k = 0; k < 6; ++k) {  // exercises the accelerated schedule (gamma = 0.35)
    float theta = 1.f / std::sqrt(1.f + 0.7f * scale);
    prm.schedule.push_back({scale, 1.f / scale, theta});
    scale *= theta;
  }
  b.primalDual(pd, data, s.put(tensor), s.put(steps), s.put(mask), prm);
  return {s.get("primaldual_u", pd.u), s.get("primaldual_ubar", pd.uBar), s.get("primaldual_v", pd.v),
          s.get("primaldual_p", pd.p), s.get("primaldual_q", pd.q)};
}

std::vector<Output> medianCase(Backend& b) {
  Session s{b};
  Host src = noise(kW, kH, 1, 18, 1.f), mask = discMask(kW, kH);
  Buffer dst = s.make(kW, kH, 1);
  b.median(dst, s.put(src), s.put(mask));
  return {s.get("median_dst", dst)};
}

std::vector<Output> accumulateCase(Backend& b) {
  Session s{b};
  Host u = noise(kW, kH, 1, 19, 0.5f), w = noise(kW, kH, 2, 20, 3.f), u0 = noise(kW, kH, 1, 21, 0.3f),
       g = tangentField(kW, kH), mask = discMask(kW, kH);
  Buffer ub = s.put(u), wb = s.put(w);
  b.accumulate(ub, wb, s.put(u0), s.put(g), s.put(mask), 0.2f);
  return {s.get("accumulate_u", ub), s.get("accumulate_w", wb)};
}

// A T265-like Kannala-Brandt lens at the odd golden size, and a pose with rotation.
FieldsParams fieldsParams() {
  FieldsParams p{};
  p.cam0 = toCameraParams(Camera::kannalaBrandt4(kW, kH, 15.2, 15.3, 22.4, 18.1, -0.0066, 0.0473, -0.0458, 0.009));
  p.cam1 = toCameraParams(Camera::kannalaBrandt4(kW, kH, 15.1, 15.2, 22.8, 17.9, -0.005, 0.039, -0.035, 0.005));
  const double c = std::cos(0.01), sn = std::sin(0.01);
  const double R[9] = {c, 0, sn, 0, 1, 0, -sn, 0, c};
  std::copy(R, R + 9, p.R);
  p.t[0] = -0.064, p.t[1] = 0.001, p.t[2] = 0.002;
  p.maxFovDeg = 160;
  p.epipoleDeg = 3;
  return p;
}

std::vector<Output> fieldsCase(Backend& b) {
  Session s{b};
  Host allowed = discMask(kW, kH);
  Buffer mask = s.put(allowed), calibration = s.make(kW, kH, 2), trajectory = s.make(kW, kH, 2);
  b.fields(mask, calibration, trajectory, fieldsParams());
  return {s.get("fields_mask", mask), s.get("fields_calibration", calibration), s.get("fields_trajectory", trajectory)};
}

std::vector<Output> triangulateCase(Backend& b) {
  Session s{b};
  Host w = noise(kW, kH, 2, 22, 1.5f), mask = discMask(kW, kH);
  // Mostly positive disparities along -x (the direction of a rig with t = (-B, 0, 0)),
  // some of them pointing away (infinitely far), some exactly zero.
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      w.at(x, y, 0) -= 1.2f;
      if ((x + y) % 11 == 0) w.at(x, y, 0) = w.at(x, y, 1) = 0.f;
    }
  Buffer radial = s.make(kW, kH, 1), points = s.make(kW, kH, 3);
  const double tPrime[3] = {-0.064, 0.001, 0.002};
  b.triangulate(radial, points, s.put(w), s.put(mask), fieldsParams().cam0, tPrime);
  return {s.get("triangulate_radial", radial), s.get("triangulate_points", points)};
}

}  // namespace

const std::vector<KernelCase>& kernelCases() {
  static const std::vector<KernelCase> cases = {{"fields", fieldsCase},
                                                {"triangulate", triangulateCase},
                                                {"warp", warpCase},
                                                {"downsample", downsampleCase},
                                                {"upsample", upsampleCase},
                                                {"structureTensor", structureTensorCase},
                                                {"warpDerivatives", warpDerivativesCase},
                                                {"primalDual", primalDualCase},
                                                {"median", medianCase},
                                                {"accumulate", accumulateCase}};
  return cases;
}

SolveInputs renderSolveInputs() {
  synth::SynthConfig cfg;
  cfg.camera = synth::defaultFisheye(97);
  cfg.camera.height = 89;
  cfg.camera.params[3] = 44.0;
  cfg.baseline = 0.15;
  cfg.seed = 12;
  cfg.samplesPerAxis = 3;
  synth::SynthPair p = synth::renderPair(cfg);
  return {p.rig, p.left, p.right};
}

void saveSolveInputs(const SolveInputs& in, const std::string& dir) {
  saveKalibr(in.rig, (std::filesystem::path(dir) / "solve_camchain.yaml").string());
  writeExr((std::filesystem::path(dir) / "solve_left.exr").string(), in.left);
  writeExr((std::filesystem::path(dir) / "solve_right.exr").string(), in.right);
}

SolveInputs loadSolveInputs(const std::string& dir) {
  return {loadKalibr((std::filesystem::path(dir) / "solve_camchain.yaml").string()),
          readExr((std::filesystem::path(dir) / "solve_left.exr").string()),
          readExr((std::filesystem::path(dir) / "solve_right.exr").string())};
}

std::vector<Output> runSolve(const SolveInputs& in, const std::string& backend) {
  Params p = preset("default");
  p.levels = 2;
  p.minWidth = 24;
  p.warps = 8;
  p.iterations = 6;
  Stereo stereo(in.rig, p, backend);
  DepthResult r = stereo.compute(in.left, in.right);
  ImageF warp(r.warp.width, 2 * r.warp.height);
  for (int y = 0; y < r.warp.height; ++y)
    for (int x = 0; x < r.warp.width; ++x) {
      warp(x, y) = r.warp(x, y).x;
      warp(x, y + r.warp.height) = r.warp(x, y).y;
    }
  return {{"solve_disparity", r.disparity}, {"solve_warp", warp}};
}

Difference compare(const ImageF& actual, const ImageF& expected, double tol) {
  Difference d;
  double num = 0, den = 0;
  for (size_t i = 0; i < expected.size(); ++i) {
    float a = actual.data[i], e = expected.data[i];
    if (!std::isfinite(e) || !std::isfinite(a)) {
      bool same = (std::isnan(a) && std::isnan(e)) || a == e;
      d.mismatchedNonFinite += !same;
      continue;
    }
    double diff = std::abs(double(a) - e);
    d.maxAbs = std::max(d.maxAbs, diff);
    num += diff * diff;
    den += double(e) * e;
    ++d.count;
    d.withinCount += diff <= tol;
  }
  d.nmse = den > 0 ? num / den : num;
  return d;
}

}  // namespace cs::golden

#include "golden_cases.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include <Eigen/Geometry>

#include "cpu_backend.hpp"
#include "curvestereo/camera.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/pipeline_params.hpp"
#include "curvestereo/stereo.hpp"
#include "golden_inputs.hpp"
#include "synth/scene.hpp"

namespace cs::golden {

PrimalDualParams primalDualCaseParams(int iterations) {
  PrimalDualParams p{20.f, 17.f, 1.2f, {}};
  float scale = 1.f;
  for (int k = 0; k < iterations; ++k) {
    const float theta = 1.f / std::sqrt(1.f + 0.7f * scale);
    p.schedule.push_back({scale, 1.f / scale, theta});
    scale *= theta;
  }
  return p;
}

namespace {
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

// A coarse estimate with a curved depth step (1.5 to 4.5 px, plus a gentle slope) and
// displacements along (1, 0.3); image 1 is image 0 moved by the fine step's displacement,
// so the window matching has a right answer; the disc mask leaves pixels bilinear.
std::vector<Output> upsampleEstimateCase(Backend& b) {
  Session s{b};
  const int cw = (kW + 1) / 2, ch = (kH + 1) / 2;
  auto near = [](float x, float y) { return x + 0.3f * y > 12.f + 0.02f * (y - 9.f) * (y - 9.f); };
  Host coarseU(cw, ch, 1), coarseW(cw, ch, 2), n1(kW, kH, 1);
  for (int y = 0; y < ch; ++y)
    for (int x = 0; x < cw; ++x) {
      const float u = (near(float(x), float(y)) ? 2.25f : 0.75f) + 0.01f * float(x);
      coarseU.at(x, y) = u;
      coarseW.at(x, y, 0) = u;
      coarseW.at(x, y, 1) = 0.3f * u;
    }
  Host n0 = texture(kW, kH, 51), mask = discMask(kW, kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      // Image 1 at x + w(x) shows image 0 at x (nearest pixel: enough to be unambiguous).
      const float u = 2.f * ((near(0.5f * (float(x) + 0.5f) - 0.5f, 0.5f * (float(y) + 0.5f) - 0.5f) ? 2.25f : 0.75f));
      const int tx = std::min(kW - 1, x + int(std::lround(u))), ty = std::min(kH - 1, y + int(std::lround(0.3f * u)));
      n1.at(tx, ty) = n0.at(x, y);
    }
  Buffer u = s.make(kW, kH, 1), w = s.make(kW, kH, 2);
  b.upsampleEstimate(u, w, s.put(coarseU), s.put(coarseW), s.put(n0), s.put(n1), s.put(mask), {2.f, 1.f, 2});
  return {s.get("upsampleestimate_u", u), s.get("upsampleestimate_w", w)};
}

// A texture under a gain and an offset that vary across the image (vignetting, exposure),
// so the window statistics differ everywhere: the local spread goes from epsilon (left)
// to 7 epsilon (right). Sigma 2.5 (radius 8) reaches over the disc's rim and the hole.
std::vector<Output> normaliseCase(Backend& b) {
  Session s{b};
  Host src = texture(kW, kH, 50, 2), mask = discMask(kW, kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const float u = float(x) / float(kW - 1), gain = 0.05f + 1.15f * u * u;
      const float offset = 0.1f * float(y) / float(kH - 1) - 0.05f;
      src.at(x, y) = gain * src.at(x, y) + offset;
    }
  Params params;
  params.normSigma = 2.5f;
  NormaliseParams np = normaliseParams(params);
  np.epsilon = 0.01f;
  Buffer dst = s.make(kW, kH, 1), moments = s.make(kW, kH, 3);
  b.normalise(dst, moments, s.put(src), s.put(mask), np);
  // The oracle's order of summation, no contraction: bit-exact on lavapipe (and CUDA with
  // IEEE division and square root). Vulkan allows 2.5-ulp division and square root: on the
  // case's values (|output| <= 2.2, local spread down to epsilon) that moves the output by
  // <= 1.7e-5 (the oracle re-run with each quotient and root off by 2.5 ulp, every sign).
  return within({s.get("normalise_dst", dst)}, {1e-4, 1e-9});
}

std::vector<Output> structureTensorCase(Backend& b) {
  Session s{b};
  Host image = texture(kW, kH, 5), mask = discMask(kW, kH);
  Buffer tensor = s.make(kW, kH, 4), steps = s.make(kW, kH, 4);
  b.structureTensor(tensor, steps, s.put(image), s.put(mask), kTensor);
  return within({s.get("tensor_tensor", tensor), s.get("tensor_steps", steps)}, {2e-4, 1e-9});
}

std::vector<Output> warpDerivativesCase(Backend& b) {
  Session s{b};
  Host i0 = texture(kW, kH, 6), i1 = texture(kW, kH, 7), traj = tangentField(kW, kH), w = noise(kW, kH, 2, 8, 2.f),
       u = noise(kW, kH, 1, 9, 2.f), mask = discMask(kW, kH);
  DataTermBuffers data{s.make(kW, kH, 1), s.make(kW, kH, 1), s.make(kW, kH, 1)};
  Buffer tangent = s.make(kW, kH, 2);
  b.warpDerivatives(data, tangent, s.put(i0), s.put(i1), s.put(traj), s.put(w), s.put(u), s.put(mask), Buffer{}, 0.f);
  return {s.get("derivatives_u0", data.u0), s.get("derivatives_iu", data.iu), s.get("derivatives_iz", data.iz),
          s.get("derivatives_tangent", tangent)};
}

// The same inputs with a confidence buffer: values below, at and above the floor (and
// zero), so both branches of max(confidence, floor) are exercised.
std::vector<Output> warpDerivativesConfidenceCase(Backend& b) {
  Session s{b};
  Host i0 = texture(kW, kH, 6), i1 = texture(kW, kH, 7), traj = tangentField(kW, kH), w = noise(kW, kH, 2, 8, 2.f),
       u = noise(kW, kH, 1, 9, 2.f), mask = discMask(kW, kH), confidence(kW, kH, 1);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      confidence.at(x, y) = (x + 2 * y) % 7 == 0 ? 0.f : hashNoise(uint32_t(y * kW + x) * 2654435761U + 40);
  DataTermBuffers data{s.make(kW, kH, 1), s.make(kW, kH, 1), s.make(kW, kH, 1)};
  Buffer tangent = s.make(kW, kH, 2);
  b.warpDerivatives(data, tangent, s.put(i0), s.put(i1), s.put(traj), s.put(w), s.put(u), s.put(mask),
                    s.put(confidence), 0.3f);
  return {s.get("derivativesconf_u0", data.u0), s.get("derivativesconf_iu", data.iu),
          s.get("derivativesconf_iz", data.iz), s.get("derivativesconf_tangent", tangent)};
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
  const PrimalDualParams prm = primalDualCaseParams(6);  // exercises the accelerated schedule
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

// --- coarse kernels (fusion points): the same results as their fine sequences ---

// primalDualCase's inputs with uBar, vBar of their own, which warpIterations replaces by u, v.
std::vector<Output> warpIterationsCase(Backend& b) {
  Session s{b};
  Host image = texture(kW, kH, 10), mask = discMask(kW, kH), tensor(kW, kH, 4), steps(kW, kH, 4);
  cpu::structureTensor(tensor.view(), steps.view(), image.view(), mask.view(), kTensor);
  Host u = noise(kW, kH, 1, 11, 1.f), v = noise(kW, kH, 2, 12, 0.1f), p = noise(kW, kH, 2, 13, 0.5f),
       q = noise(kW, kH, 4, 14, 0.2f), u0 = noise(kW, kH, 1, 15, 1.f), iu = noise(kW, kH, 1, 16, 0.1f),
       iz = noise(kW, kH, 1, 17, 0.05f), uBar = noise(kW, kH, 1, 60, 1.f), vBar = noise(kW, kH, 2, 61, 0.1f);
  PrimalDualBuffers pd{s.put(u), s.put(uBar), s.put(v), s.put(vBar), s.put(p), s.put(q)};
  DataTermBuffers data{s.put(u0), s.put(iu), s.put(iz)};
  const PrimalDualParams prm = primalDualCaseParams(7);
  b.warpIterations(pd, data, s.put(tensor), s.put(steps), s.put(mask), prm);
  return {s.get("warpiterations_u", pd.u), s.get("warpiterations_ubar", pd.uBar),
          s.get("warpiterations_v", pd.v), s.get("warpiterations_vbar", pd.vBar),
          s.get("warpiterations_p", pd.p), s.get("warpiterations_q", pd.q)};
}

// A warp's end (median, accumulate) and, with nextWarp, the next warp's data term, on the
// inputs of the accumulate and warpDerivatives cases; the confidence (below, at and above
// the floor) only with `weighted`.
std::vector<Output> warpTailOutputs(Backend& b, const std::string& prefix, bool median, bool nextWarp, bool weighted) {
  Session s{b};
  Host u = noise(kW, kH, 1, 19, 1.5f), w = noise(kW, kH, 2, 20, 3.f), u0 = noise(kW, kH, 1, 21, 1.3f),
       g = tangentField(kW, kH), mask = discMask(kW, kH), i0 = texture(kW, kH, 6), i1 = texture(kW, kH, 7),
       traj = tangentField(kW, kH), confidence(kW, kH, 1), iu = noise(kW, kH, 1, 62, 1.f),
       iz = noise(kW, kH, 1, 63, 1.f);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      confidence.at(x, y) = (x + 2 * y) % 7 == 0 ? 0.f : hashNoise(uint32_t(y * kW + x) * 2654435761U + 40);
      const float a = 0.2f - 0.01f * x + 0.025f * y;  // a tangent field unlike the trajectory
      g.at(x, y, 0) = std::cos(a), g.at(x, y, 1) = std::sin(a);
    }
  const WarpBuffers warp{s.put(u),
                         s.put(w),
                         s.put(g),
                         s.put(mask),
                         {s.put(u0), s.put(iu), s.put(iz)},
                         s.put(i0),
                         s.put(i1),
                         s.put(traj),
                         weighted ? s.put(confidence) : Buffer{},
                         0.3f};
  const Buffer scratch = median ? s.make(kW, kH, 1) : Buffer{};
  b.warpTail(warp, scratch, 0.2f, nextWarp);
  std::vector<Output> out = {s.get(prefix + "_u", warp.u), s.get(prefix + "_w", warp.w)};
  if (median) out.push_back(s.get(prefix + "_median", scratch));
  if (nextWarp)
    for (const auto& [name, buffer] : {std::pair<const char*, Buffer>{"_u0", warp.data.u0},
                                       {"_iu", warp.data.iu},
                                       {"_iz", warp.data.iz},
                                       {"_tangent", warp.tangent}})
      out.push_back(s.get(prefix + name, buffer));
  return out;
}

std::vector<Output> warpTailCase(Backend& b) { return warpTailOutputs(b, "warptail", true, true, true); }
std::vector<Output> warpTailLastCase(Backend& b) { return warpTailOutputs(b, "warptaillast", true, false, false); }
std::vector<Output> warpTailNoMedianCase(Backend& b) {
  return warpTailOutputs(b, "warptailnomedian", false, true, false);
}

std::vector<Output> fieldsCase(Backend& b) {
  Session s{b};
  Host allowed = discMask(kW, kH);
  Buffer mask = s.put(allowed), calibration = s.make(kW, kH, 2), trajectory = s.make(kW, kH, 2);
  b.fields(mask, calibration, trajectory, fieldsParams());
  // Float camera models on the GPUs against the oracle's double ones.
  return within(
      {s.get("fields_mask", mask), s.get("fields_calibration", calibration), s.get("fields_trajectory", trajectory)},
      {2e-3, 1e-9});
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
  // Metres: far points amplify the rounding of their rays.
  return within({s.get("triangulate_radial", radial), s.get("triangulate_points", points)}, {1e-2, 1e-8});
}

// --- plane sweep ---

// Stretches values linearly onto [0, 1] (a contrasty texture keeps ZNCC far from its
// flat-window regularisation).
Host stretched(Host h) {
  const auto [lo, hi] = std::minmax_element(h.v.begin(), h.v.end());
  const float a = *lo, range = *hi - *lo;
  for (float& v : h.v) v = (v - a) / range;
  return h;
}

// Bilinear sample of a 1-channel host image; false outside [0, w-1] x [0, h-1].
bool sampleHost(Host& img, float x, float y, float& value) {
  if (!(x >= 0.f && y >= 0.f && x <= float(img.w - 1) && y <= float(img.h - 1))) return false;
  const int x0 = std::min(int(x), img.w - 2), y0 = std::min(int(y), img.h - 2);
  const float fx = x - float(x0), fy = y - float(y0);
  value = (img.at(x0, y0) * (1.f - fx) + img.at(x0 + 1, y0) * fx) * (1.f - fy) +
          (img.at(x0, y0 + 1) * (1.f - fx) + img.at(x0 + 1, y0 + 1) * fx) * fy;
  return true;
}

// The fields' T265-like lens and a baseline mostly along -x with some y and z, so the
// hypotheses move along curves, not rows.
SweepParams sweepParams(double qMax, int planes, int radius) {
  SweepParams p{};
  p.cam = fieldsParams().cam0;
  p.t[0] = -0.1, p.t[1] = 0.004, p.t[2] = 0.006;
  p.qMax = qMax;
  p.planes = planes;
  p.radius = radius;
  p.p1 = 0.05f;
  p.p2 = 0.5f;
  p.flatVariance = 1e-5f;
  return p;
}

// Where pixel (x, y) sees the sphere of inverse depth q in the other view, in double like
// the oracle; false where the ray or its projection is invalid.
bool hypothesis(const BuiltCamera& cam, const double t[3], double x, double y, double q, Vec2<double>& px) {
  Vec3<double> ray;
  if (!cam.unproject(Vec2<double>(x, y), ray)) return false;
  return cam.project(Vec3<double>(ray.x() + q * t[0], ray.y() + q * t[1], ray.z() + q * t[2]), px);
}

// Distance from px to the border of the image rectangle [-0.5, w-0.5] x [-0.5, h-0.5].
double borderDistance(const Camera& cam, const Vec2<double>& px) {
  return std::min({std::abs(px.x() + 0.5), std::abs(px.x() - (cam.width - 0.5)), std::abs(px.y() + 0.5),
                   std::abs(px.y() - (cam.height - 0.5))});
}

// A baseline reaching backwards (t_z = -0.1) and qMax = 4: up to 9 px of motion at the
// centre, and about 180 hypotheses of the rim leave the image (-1); the moved points stay
// >= 0.43 from the other centre, so no projection is ill-conditioned. A float camera model
// puts a projection ~1e-3 px from where double does, so reference pixels with a hypothesis
// within 0.05 px of the image border are left out of the mask (backends must agree on
// which samples exist).
std::vector<Output> sweepWarpCase(Backend& b) {
  Session s{b};
  SweepParams p = sweepParams(4.0, 9, 2);
  p.t[2] = -0.1;
  const BuiltCamera cam(toCamera(p.cam));
  Host image = texture(kW, kH, 30), mask = discMask(kW, kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int k = 0; k < p.planes && mask.at(x, y) != 0.f; ++k) {
        Vec2<double> px;
        if (hypothesis(cam, p.t, x, y, p.qMax * k / (p.planes - 1), px) && borderDistance(cam.camera(), px) < 0.05)
          mask.at(x, y) = 0.f;
      }
  Buffer volume = s.make(kW, kH, p.planes);
  b.sweepWarp(volume, s.put(image), s.put(mask), p);
  // Sweep geometry like the fields (float camera models against double): a hypothesis lands
  // up to ~2e-3 px away, and the texture's steps are <= 0.13 per px (so <= 2.6e-4).
  return within({s.get("sweepwarp_volume", volume)}, {5e-4, 1e-9});
}

// A volume with a known answer: plane k at pixel x is the reference shifted by
// (k - k*(x)) * 1.3 px along (1, 0.5), -1 where that leaves the image; k* is a gentle ramp
// (1.3 .. 6.7 planes, 0.1 plane per px, so a 5x5 window is nearly one hypothesis).
// Unsampleable patches: all planes in a 4x4 square (its centre scores nothing: (-1, 2)),
// the first three planes in another (the parabola lacks a neighbour there). A texture of
// short correlation (one blur pass) keeps the window variance high, so the one-pass float
// ZNCC is within 4e-5 of the exact one (measured against double sums); and the parabola's
// curvature is >= 0.06 wherever it is used, so that moves q by ~1e-4 at most (near-ties
// between two planes are harmless: both winners give the same vertex).
struct CostInputs {
  SweepParams p;
  Host reference, mask, volume;
};

CostInputs sweepCostInputs() {
  CostInputs in{sweepParams(2.0, 9, 2), stretched(texture(kW, kH, 31, 1)), discMask(kW, kH), Host(kW, kH, 9)};
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const float kStar = 1.3f + 0.07f * float(x) + 0.065f * float(y);
      for (int k = 0; k < in.p.planes; ++k) {
        float v = -1.f;
        const float shift = 1.3f * (float(k) - kStar);
        const bool hole = (x >= 30 && x < 34 && y >= 8 && y < 12) || (k < 3 && x >= 8 && x < 15 && y >= 20 && y < 27);
        if (hole || !sampleHost(in.reference, float(x) + shift, float(y) + 0.5f * shift, v)) v = -1.f;
        in.volume.at(x, y, k) = v;
      }
    }
  return in;
}

std::vector<Output> sweepCostCase(Backend& b) {
  Session s{b};
  CostInputs in = sweepCostInputs();
  Buffer costs = s.make(kW, kH, in.p.planes);
  b.sweepCost(costs, s.put(in.reference), s.put(in.volume), s.put(in.mask), in.p);
  // 1 - ZNCC from one-pass float sums: the oracle's own cost is ~4e-5 from the exact one
  // (float against double sums on the case), a backend summing in another order as far again.
  return within({s.get("sweepcost_costs", costs)}, {2e-4, 1e-9});
}

// Costs with a valley at a hypothesis that ramps across the image and jumps by three
// planes along a slanted edge (so paths take both p1 and p2 steps), noise, unscored
// hypotheses (2, capped to 1 by the aggregation) and an unmasked patch inside the disc
// (paths restart after it). The valley's position scales with planes / 9 (exactly 1 at 9).
Host aggregationCosts(const SweepParams& p, Host& mask) {
  Host costs(kW, kH, p.planes);
  const float scale = float(p.planes - 1) / 8.f;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const float valley = scale * (2.f + 0.05f * float(x) + (x + y / 2 > 30 ? 3.f : 0.f));
      for (int k = 0; k < p.planes; ++k) {
        const uint32_t i = uint32_t((y * kW + x) * p.planes + k);
        const float d = float(k) - valley;
        float c = 0.1f + 0.04f * d * d + 0.3f * hashNoise(i * 13u + 41);
        if (hashNoise(i * 17u + 42) < 0.05f || c > 2.f) c = 2.f;
        costs.at(x, y, k) = mask.at(x, y) != 0.f ? c : 2.f;
      }
    }
  return costs;
}

Host holedDisc() {
  Host mask = discMask(kW, kH);
  for (int y = 14; y < 18; ++y)
    for (int x = 20; x < 26; ++x) mask.at(x, y) = 0.f;
  return mask;
}

// The aggregation of aggregationCosts over a disc with a hole, at `planes` hypotheses.
std::vector<Output> aggregateAt(Backend& b, int planes, const char* name) {
  Session s{b};
  const SweepParams p = sweepParams(2.0, planes, 2);
  Host mask = holedDisc();
  Buffer aggregated = s.make(kW, kH, p.planes);
  Host costs = aggregationCosts(p, mask);
  b.sweepAggregate(aggregated, s.put(costs), s.put(mask), p);
  // Minima and float adds in a fixed order: exact on every backend (the bound allows printing).
  return within({s.get(name, aggregated)}, {1e-6, 1e-15});
}

std::vector<Output> sweepAggregateCase(Backend& b) { return aggregateAt(b, 9, "sweepaggregate_volume"); }

// The same at 40 planes: a GPU holding planes in 32-wide chunks (CUDA: a warp's lanes)
// passes neighbours across the chunks' seam and leaves most of the last chunk unused.
std::vector<Output> sweepAggregateChunksCase(Backend& b) { return aggregateAt(b, 40, "sweepaggregate_chunks"); }

// Aggregated costs with a clear parabola around a ramping hypothesis (curvature >= 0.5
// per path, so the vertex is well conditioned), costs with unscored hypotheses: the
// winner among the scored, no parabola beside an unscored one, (-1, 2) where none scored.
std::vector<Output> sweepSelectCase(Backend& b) {
  Session s{b};
  const SweepParams p = sweepParams(2.0, 9, 2);
  Host mask = holedDisc(), aggregated(kW, kH, p.planes), costs(kW, kH, p.planes);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int k = 0; k < p.planes; ++k) {
        const uint32_t i = uint32_t((y * kW + x) * p.planes + k);
        const float d = float(k) - (0.6f + 0.11f * float(x) + 0.09f * float(y));
        aggregated.at(x, y, k) = 4.f * (0.2f + 0.5f * d * d) + 0.01f * hashNoise(i * 19u + 43);
        const bool none = (x >= 40 && x < 44 && y >= 10 && y < 13) || hashNoise(i * 23u + 44) < 0.04f;
        costs.at(x, y, k) = none ? 2.f : 0.1f + hashNoise(i * 29u + 45);
      }
  Buffer best = s.make(kW, kH, 2);
  b.sweepSelect(best, s.put(aggregated), s.put(costs), s.put(mask), p);
  // Exact inputs, one float division in the parabola, q in double (float on Vulkan devices
  // without float64): ~1e-6 of q.
  return within({s.get("sweepselect_best", best)}, {1e-5, 1e-12});
}

// A reference sweep with smooth inverse depths (0.3..2.8 /m, up to ~4 px of motion), holes
// (q = -1), costs up to 1.15; the other view's answer is the reference's field at the
// landing pixel (nearly consistent: round trips of a fraction of a pixel) except in a band
// where it is far off, with holes of its own. u and w start as noise (the coarse-to-fine
// estimate the sweep replaces where it is confident).
// Well-conditioned by construction (computed on the host in double, like the oracle):
// inverse depths whose landing point is within 0.05 px of a nearest-pixel tie (x.5) or of
// the image border are nudged, so backends agree on which neighbour is read; pixels whose
// round trip e is within 5 % of a threshold (e = tol, or the e of acceptConfidence) lose
// their hypothesis, so no backend's rounding can flip a replace / keep decision.
std::vector<Output> sweepInitialiseCase(Backend& b) {
  Session s{b};
  const SweepParams p = sweepParams(3.0, 9, 2);
  const double back[3] = {-p.t[0], -p.t[1], -p.t[2]};
  ConsistencyParams consistency{};
  consistency.tolerancePx = 1.5f;
  consistency.acceptConfidence = 0.3f;
  consistency.maxCost = 0.85f;  // the costs below span 0.05 .. 1.15: some winners are refused
  const double eAccept = std::sqrt(-std::log(double(consistency.acceptConfidence)));
  const BuiltCamera cam(toCamera(p.cam));
  Host field = stretched(texture(kW, kH, 34)), mask = discMask(kW, kH), best(kW, kH, 2), other(kW, kH, 2);
  // False when pixel (x, y) at inverse depth q lands within `margin` px of the image
  // border or of a nearest-pixel tie.
  auto clear = [&](int x, int y, double q, double margin) {
    Vec2<double> px;
    if (!hypothesis(cam, p.t, x, y, q, px) || !cam.inImage(px, -margin)) return true;
    auto tie = [&](double v) { return std::abs(v - std::floor(v) - 0.5) < margin; };
    return borderDistance(cam.camera(), px) >= margin && !tie(px.x()) && !tie(px.y());
  };
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const uint32_t i = uint32_t(y * kW + x);
      double q = 0.3 + 2.5 * field.at(x, y);
      for (int n = 0; n < 40 && !clear(x, y, q, 0.05); ++n) q *= 0.985;
      best.at(x, y, 0) = hashNoise(i * 3u + 35) < 0.08f ? -1.f : float(q);
      best.at(x, y, 1) = 0.05f + 1.1f * hashNoise(i * 5u + 36);
      float qOther = float(0.3 + 2.5 * field.at(x, y));
      if (x >= 28 && x < 33) qOther += 1.5f;  // an inconsistent band
      if (hashNoise(i * 7u + 37) < 0.06f) qOther = -1.f;
      other.at(x, y, 0) = qOther;
      other.at(x, y, 1) = 0.2f;
    }
  Host u0 = noise(kW, kH, 1, 38, 3.f), w0 = noise(kW, kH, 2, 39, 3.f);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      Vec2<double> there, returned;
      if (!mask.at(x, y) || best.at(x, y, 0) < 0.f || !hypothesis(cam, p.t, x, y, best.at(x, y, 0), there) ||
          !cam.inImage(there))
        continue;
      const int nx = int(std::lround(there.x())), ny = int(std::lround(there.y()));
      if (nx < 0 || ny < 0 || nx >= kW || ny >= kH || !mask.at(nx, ny) || other.at(nx, ny, 0) < 0.f ||
          !hypothesis(cam, back, there.x(), there.y(), other.at(nx, ny, 0), returned) || !cam.inImage(returned))
        continue;
      const double e = std::hypot(returned.x() - x, returned.y() - y) / consistency.tolerancePx;
      if (std::abs(e - 1.0) < 0.05 || std::abs(e - eAccept) < 0.05) best.at(x, y, 0) = -1.f;
    }
  Buffer u = s.put(u0), w = s.put(w0), confidence = s.make(kW, kH, 1);
  b.sweepInitialise(u, w, confidence, s.put(best), s.put(other), s.put(mask), p, consistency);
  // Float camera models again: w and u are positions ~2e-3 px off, and the confidence's slope
  // in e is at most sqrt(2/e) / tol = 0.57 per px at the case's tol = 1.5 px.
  return within({s.get("sweepinit_u", u), s.get("sweepinit_w", w), s.get("sweepinit_confidence", confidence)},
                {2e-3, 1e-8});
}

// --- the band sweep ---

// A band's first hypothesis clamped to the range, as sweepBandWarp places it.
int bandStart(int centre, const SweepParams& p) { return std::clamp(centre - p.band / 2, 0, p.planes - p.band); }

// A coarse sweep's answer (half resolution, the fine grid's coarse pixel as
// sweepBandWarp finds it) whose hypotheses ramp across the image with holes (-1), at
// q = qMax (n + 0.3) / (planes - 1): 0.2 plane from a rounding tie, so backends agree on
// the centre n. The fine mask leaves out pixels with a band hypothesis within 0.05 px of
// the image border (as sweepWarpCase), the bands placed by the oracle (a pixel's band
// depends on the coarse answer and its own mask bit only).
std::vector<Output> sweepBandWarpCase(Backend& b) {
  Session s{b};
  SweepParams p = sweepParams(4.0, 40, 2);
  p.t[2] = -0.1;
  p.band = 8;
  const int cw = (kW + 1) / 2, ch = (kH + 1) / 2;
  Host coarse(cw, ch, 2);
  for (int y = 0; y < ch; ++y)
    for (int x = 0; x < cw; ++x) {
      const int n = int(2.f + 1.4f * float(x) + 0.6f * float(y)) % p.planes;
      const bool hole = hashNoise(uint32_t(y * cw + x) * 7u + 61) < 0.1f;
      coarse.at(x, y, 0) = hole ? -1.f : float(p.qMax * (n + 0.3) / (p.planes - 1));
      coarse.at(x, y, 1) = 0.3f;
    }
  const BuiltCamera cam(toCamera(p.cam));
  Host image = texture(kW, kH, 30), mask = discMask(kW, kH), oracleVolume(kW, kH, p.band), starts(kW, kH, 1);
  cpu::sweepBandWarp(oracleVolume.view(), starts.view(), image.view(), coarse.view(), mask.view(), p, 0.5f);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const int start = int(starts.at(x, y));
      if (start < 0) continue;
      for (int k = 0; k < p.band && mask.at(x, y) != 0.f; ++k) {
        Vec2<double> px;
        if (hypothesis(cam, p.t, x, y, p.qMax * (start + k) / (p.planes - 1), px) &&
            borderDistance(cam.camera(), px) < 0.05)
          mask.at(x, y) = 0.f;
      }
    }
  Buffer volume = s.make(kW, kH, p.band), first = s.make(kW, kH, 1);
  b.sweepBandWarp(volume, first, s.put(image), s.put(coarse), s.put(mask), p, 0.5f);
  // The volume as sweepWarp's; the first hypotheses are integers from proposals 0.2 plane
  // from a rounding tie: exact.
  return {within({s.get("sweepbandwarp_volume", volume)}, {5e-4, 1e-9})[0],
          within({s.get("sweepbandwarp_first", first)}, {0.0, 0.0})[0]};
}

// Each pixel's true hypothesis h*(x) ramps and jumps by `jump` planes along a slanted edge
// (9, more than the band of 8: windows across it find few shared hypotheses); its band starts 4 below
// it, or 2 below in a stripe (neighbouring bands overlap in part); a patch has no band
// (-1). Plane h at a pixel is the reference shifted by 1.3 (h - h*) px along (1, 0.5), as
// sweepCostInputs.
std::vector<Output> bandCostAt(Backend& b, int radius, const char* name, int band = 8, float jump = 9.f,
                               int planes = 40) {
  Session s{b};
  SweepParams p = sweepParams(2.0, planes, radius);
  p.band = band;
  Host reference = stretched(texture(kW, kH, 31, 1)), mask = discMask(kW, kH);
  Host volume(kW, kH, p.band), first(kW, kH, 1);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const float hStar = 6.3f + 0.4f * float(x) + 0.2f * float(y) + (x + y / 2 > 28 ? jump : 0.f);
      const bool none = x >= 30 && x < 34 && y >= 8 && y < 12;
      const int start = none ? -1 : bandStart(int(hStar) - (y % 7 < 2 ? 2 : 0) + p.band / 2 - 4, p);
      first.at(x, y) = float(start);
      for (int k = 0; k < p.band; ++k) {
        float v = -1.f;
        const float shift = 1.3f * (float(start + k) - hStar);
        if (none || !sampleHost(reference, float(x) + shift, float(y) + 0.5f * shift, v)) v = -1.f;
        volume.at(x, y, k) = v;
      }
    }
  Buffer costs = s.make(kW, kH, p.band);
  b.sweepBandCost(costs, s.put(reference), s.put(volume), s.put(first), s.put(mask), p);
  // As sweepCost's; at radius 1 a window holds 5 to 9 samples: smaller variances, so Vulkan's
  // 2.5-ulp division and square root move 1 - ZNCC further (2.8e-4 measured on NVIDIA's
  // driver at one pixel, NMSE 1.7e-11; CUDA and lavapipe exact).
  return within({s.get(name, costs)}, radius == 1 ? Tolerance{5e-4, 1e-9} : Tolerance{2e-4, 1e-9});
}

std::vector<Output> sweepBandCostCase(Backend& b) { return bandCostAt(b, 2, "sweepbandcost_costs"); }

// Other windows: GPUs specialise their tiles per radius (CUDA: 0 to 3, a loop above).
std::vector<Output> sweepBandCostRadius1Case(Backend& b) { return bandCostAt(b, 1, "sweepbandcost_radius1"); }
std::vector<Output> sweepBandCostRadius3Case(Backend& b) { return bandCostAt(b, 3, "sweepbandcost_radius3"); }
std::vector<Output> sweepBandCostRadius4Case(Backend& b) { return bandCostAt(b, 4, "sweepbandcost_radius4"); }
// 32-wide bands that jump by 50 planes: the rows across the edge span more hypotheses than
// a GPU keeps a row's column partials for (CUDA: 64), so their windows are summed alone.
std::vector<Output> sweepBandCostJumpCase(Backend& b) { return bandCostAt(b, 2, "sweepbandcost_jump", 32, 50.f, 120); }

// aggregationCosts' valley, seen through bands that follow it with a jitter of up to two
// planes each way (so neighbouring bands are shifted against each other), jump with it,
// jump by more than the band in a stripe (paths see no shared hypothesis there), and a
// patch without a band (paths restart after it, as after the unmasked hole).
std::vector<Output> bandAggregateAt(Backend& b, int planes, int band, const char* name) {
  Session s{b};
  SweepParams p = sweepParams(2.0, planes, 2);
  p.band = band;
  Host mask = holedDisc(), costs(kW, kH, band), first(kW, kH, 1);
  const float scale = float(planes - 1) / 40.f;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const uint32_t i = uint32_t(y * kW + x);
      const float valley = scale * (6.f + 0.5f * float(x) + (x + y / 2 > 30 ? 12.f : 0.f));
      const int jitter = int(5.f * hashNoise(i * 31u + 47)) - 2 + (y == 5 && x % 3 == 0 ? band + 3 : 0);
      const bool none = x >= 10 && x < 13 && y >= 22 && y < 26;
      const int start = none ? -1 : bandStart(int(valley) + jitter, p);
      first.at(x, y) = float(start);
      for (int k = 0; k < band; ++k) {
        const float d = float(start + k) - valley;
        float c = 0.1f + 0.04f * d * d + 0.3f * hashNoise((i * uint32_t(band) + uint32_t(k)) * 13u + 41);
        if (hashNoise((i * uint32_t(band) + uint32_t(k)) * 17u + 42) < 0.05f || c > 2.f) c = 2.f;
        costs.at(x, y, k) = mask.at(x, y) != 0.f && !none ? c : 2.f;
      }
    }
  Buffer aggregated = s.make(kW, kH, band);
  b.sweepBandAggregate(aggregated, s.put(costs), s.put(first), s.put(mask), p);
  return within({s.get(name, aggregated)}, {1e-6, 1e-15});  // as sweepAggregate's
}

std::vector<Output> sweepBandAggregateCase(Backend& b) {
  return bandAggregateAt(b, 40, 12, "sweepbandaggregate_volume");
}

// A full 32-wide band (CUDA: every lane of the warp holds a hypothesis).
std::vector<Output> sweepBandAggregateWideCase(Backend& b) {
  return bandAggregateAt(b, 64, 32, "sweepbandaggregate_wide");
}

// sweepSelectCase's parabolas around a ramping hypothesis, seen through bands that
// follow it except in two stripes where they lie wholly below or above it (the winner on
// the band's edge: refused), and at the range's ends (the first and the last band: kept).
std::vector<Output> sweepBandSelectCase(Backend& b) {
  Session s{b};
  SweepParams p = sweepParams(2.0, 40, 2);
  p.band = 8;
  Host mask = holedDisc(), aggregated(kW, kH, p.band), costs(kW, kH, p.band), first(kW, kH, 1);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const float hStar = -0.4f + 0.9f * float(x) + 0.05f * float(y);
      int start = bandStart(int(std::floor(hStar + 0.5f)), p);
      if (y >= 6 && y < 9) start = std::max(0, start - 6);
      if (y >= 12 && y < 15) start = std::min(p.planes - p.band, start + 6);
      first.at(x, y) = float(start);
      for (int k = 0; k < p.band; ++k) {
        const uint32_t i = uint32_t((y * kW + x) * p.band + k);
        const float d = float(start + k) - hStar;
        aggregated.at(x, y, k) = 4.f * (0.2f + 0.5f * d * d) + 0.01f * hashNoise(i * 19u + 43);
        const bool none = (x >= 40 && x < 44 && y >= 10 && y < 13) || hashNoise(i * 23u + 44) < 0.04f;
        costs.at(x, y, k) = none ? 2.f : 0.1f + hashNoise(i * 29u + 45);
      }
    }
  Buffer best = s.make(kW, kH, 2);
  b.sweepBandSelect(best, s.put(aggregated), s.put(costs), s.put(first), s.put(mask), p);
  return within({s.get("sweepbandselect_best", best)}, {1e-5, 1e-12});  // as sweepSelect's
}

}  // namespace

const std::vector<KernelCase>& kernelCases() {
  static const std::vector<KernelCase> cases = {
      {"fields", fieldsCase},
      {"triangulate", triangulateCase},
      {"warp", warpCase},
      {"downsample", downsampleCase},
      {"upsample", upsampleCase},
      {"upsampleEstimate", upsampleEstimateCase},
      {"normalise", normaliseCase},
      {"structureTensor", structureTensorCase},
      {"warpDerivatives", warpDerivativesCase},
      {"warpDerivatives+confidence", warpDerivativesConfidenceCase},
      {"primalDual", primalDualCase},
      {"median", medianCase},
      {"accumulate", accumulateCase},
      {"warpIterations", warpIterationsCase},
      {"warpTail", warpTailCase},
      {"warpTail, last warp", warpTailLastCase},
      {"warpTail, no median", warpTailNoMedianCase},
      {"sweepWarp", sweepWarpCase},
      {"sweepCost", sweepCostCase},
      {"sweepAggregate", sweepAggregateCase},
      {"sweepAggregate, 40 planes", sweepAggregateChunksCase},
      {"sweepSelect", sweepSelectCase},
      {"sweepInitialise", sweepInitialiseCase},
      {"sweepBandWarp", sweepBandWarpCase},
      {"sweepBandCost", sweepBandCostCase},
      {"sweepBandCost, radius 1", sweepBandCostRadius1Case},
      {"sweepBandCost, radius 3", sweepBandCostRadius3Case},
      {"sweepBandCost, radius 4", sweepBandCostRadius4Case},
      {"sweepBandCost, 32-wide bands jumping 50", sweepBandCostJumpCase},
      {"sweepBandAggregate", sweepBandAggregateCase},
      {"sweepBandAggregate, 32-wide band", sweepBandAggregateWideCase},
      {"sweepBandSelect", sweepBandSelectCase},
      {"carryEstimate", carryEstimateCase},
      {"carryEstimate, coarser grid of camera 1'", carryEstimateCoarseCase},
      {"temporalFilter", temporalFilterCase},
      {"plainSupport", plainSupportCase},
      {"fillPlanes", fillPlanesCase},
      {"roundTrip", roundTripCase},
      {"resultConfidence", resultConfidenceCase},
      {"resultConfidence, no sweep or round trip, radius 1", resultConfidenceAloneCase},
      {"finishResult", finishResultCase},
      {"panoramaPlace", panoramaPlaceCase},
      {"panoramaSplat and panoramaResolve", panoramaSplatCase}};
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
  Params p = preset("variational");
  p.edgeUpsample = true;  // as the sweep presets: the whole solve covers upsampleEstimate
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
  return {{"solve_disparity", r.disparity, Tolerance{}}, {"solve_warp", warp, Tolerance{}}};
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

// The Vulkan backend's kernels: each Backend kernel as the dispatches of its shaders
// (../shaders), with the parameter blocks and push constants they read. Backend has checked
// every kernel's arguments against its contract (backend.hpp).
#include <algorithm>
#include <cmath>
#include <type_traits>

#include "curvestereo/camera.hpp"
#include "curvestereo/image.hpp"
#include "normalise.hpp"
#include "vulkan_impl.hpp"

namespace cs::vk {

namespace {

// ---------------------------------------------------------------------------------------
// Parameter blocks the camera shaders read (mirrors of the GLSL structs, std430).

template <class S>
struct VkCam {
  int32_t model, width, height, pad;
  S p[8];
  S d[4];
};
static_assert(sizeof(VkCam<double>) == 112 && sizeof(VkCam<float>) == 64, "VkCam must match the GLSL Cam");

template <class S>
struct VkFieldsParams {
  VkCam<S> cam0, cam1;
  S R[9];
  S tPrime[3];
  S tDir[3];
  S halfFov;
  S epipole;
  int32_t useFov;
};

template <class S>
struct VkTriangulateParams {
  VkCam<S> cam0;
  S tPrime[3];
};

template <class S>
struct VkSweepParams {
  VkCam<S> cam;
  S t[3];
  S qMax;
};

template <class S>
VkCam<S> toVkCam(const CameraParams& c) {
  VkCam<S> out{};
  out.model = c.model;
  out.width = c.width;
  out.height = c.height;
  for (int i = 0; i < 8; ++i) out.p[i] = S(c.params[i]);
  const CameraConstants k = cameraConstants(c);
  out.d[0] = S(k.a);
  out.d[1] = S(k.b);
  return out;
}

// ---------------------------------------------------------------------------------------
// Push constants (mirrors of each shader's push_constant block).

struct PcWarp {
  Addr dst, src, flow;
  int32_t w, h, nc, sw, sh;
};
struct PcDownsample {
  Addr dst, src;
  int32_t w, h, nc, sw, sh, radius;
  float scale, sigma;
};
struct PcUpsample {
  Addr dst, src;
  int32_t w, h, nc, sw, sh;
  float scale, valueScale;
};
struct PcBlur {
  Addr dst, src;
  int32_t w, h, radius, dir;
  float sigma;
};
struct PcTensor {
  Addr tensor, smoothed;
  int32_t w, h;
  float beta, eta, wMin;
};
struct PcSteps {
  Addr steps, tensor, mask;
  int32_t w, h;
  float alpha0, alpha1;
};
struct PcWarpDerivatives {
  Addr u0, iu, iz, tangent, i0, i1, trajectory, w, u, mask, confidence;  // confidence: mask when absent
  int32_t width, height, hasConfidence;
  float weightFloor;
};
struct PcDual {
  Addr uBar, vBar, p, q, tensor, steps, mask;
  int32_t w, h;
  float sigmaScale, alpha0, alpha1;
};
struct PcPrimal {
  Addr u, uBar, v, vBar, p, q, u0, iu, iz, tensor, steps, mask;
  int32_t w, h;
  float tauScale, theta, lambda, alpha0, alpha1;
};
struct PcMedian {
  Addr dst, src, mask;
  int32_t w, h;
};
struct PcAccumulate {
  Addr u, w, u0, tangent, mask;
  int32_t width, height;
  float duMax;
};
struct PcFields {
  Addr mask, calibration, trajectory, params;
  int32_t w, h;
};
struct PcTriangulate {
  Addr radial, points, w, mask, params;
  int32_t width, height;
};
struct PcSweepWarp {
  Addr volume, image, mask, params;
  int32_t width, height, planes;
};
struct PcSweepCost {
  Addr costs, reference, volume, mask;
  int32_t width, height, planes, radius;
  float flatVariance;
};
struct PcSweepAggregate {
  Addr aggregated, spare, costs, mask;
  int32_t width, height, planes;
  float p1, p2;
};
struct PcSweepCombine {
  Addr aggregated, spare;
  int32_t count;
};
struct PcSweepSelect {
  Addr best, aggregated, costs, mask, params;
  int32_t width, height, planes;
};
struct PcSweepInitialise {
  Addr u, w, confidence, best, other, mask, params;
  int32_t width, height;
  float tolerancePx, acceptConfidence;
  int32_t pass, planes;
};
static_assert(sizeof(PcPrimal) <= kPushBytes, "push constants exceed the guaranteed 128 bytes");

}  // namespace

// ---- kernels ----

void VulkanBackend::doFields(const Buffer& mask, const Buffer& calibration, const Buffer& trajectory,
                             const FieldsParams& p) {
  // The same quantities core/src/fields.cpp derives per pixel, derived once here.
  double tPrime[3];
  for (int i = 0; i < 3; ++i) tPrime[i] = p.R[0 * 3 + i] * p.t[0] + p.R[1 * 3 + i] * p.t[1] + p.R[2 * 3 + i] * p.t[2];
  const double tn = std::sqrt(tPrime[0] * tPrime[0] + tPrime[1] * tPrime[1] + tPrime[2] * tPrime[2]);
  constexpr double kDegToRad = M_PI / 180.0;
  auto setParams = [&](auto& prm) {
    using S = std::remove_reference_t<decltype(prm.R[0])>;
    prm.cam0 = toVkCam<S>(p.cam0);
    prm.cam1 = toVkCam<S>(p.cam1);
    for (int i = 0; i < 9; ++i) prm.R[i] = S(p.R[i]);
    for (int i = 0; i < 3; ++i) {
      prm.tPrime[i] = S(tPrime[i]);
      prm.tDir[i] = S(tn > 0 ? tPrime[i] / tn : tPrime[i]);
    }
    prm.halfFov = S(0.5 * p.maxFovDeg * kDegToRad);
    prm.epipole = S(p.epipoleDeg * kDegToRad);
    prm.useFov = p.maxFovDeg > 0 ? 1 : 0;
  };
  Addr block;
  if (float64_) {
    VkFieldsParams<double> prm{};
    setParams(prm);
    block = paramBlock(&prm, sizeof(prm));
  } else {
    VkFieldsParams<float> prm{};
    setParams(prm);
    block = paramBlock(&prm, sizeof(prm));
  }
  invalidateFrame();  // a new pose: the recorded frame's triangulation is stale
  PcFields pc{addr(mask), addr(calibration), addr(trajectory), block, mask.width, mask.height};
  dispatch(float64_ ? kFieldsF64 : kFieldsF32, pc, mask.width, mask.height);
}

void VulkanBackend::doTriangulate(const Buffer& radial, const Buffer& points, const Buffer& w, const Buffer& mask,
                                  const CameraParams& cam0, const double tPrime[3]) {
  Addr block;
  if (float64_) {
    VkTriangulateParams<double> prm{};
    prm.cam0 = toVkCam<double>(cam0);
    for (int i = 0; i < 3; ++i) prm.tPrime[i] = tPrime[i];
    block = paramBlock(&prm, sizeof(prm));
  } else {
    VkTriangulateParams<float> prm{};
    prm.cam0 = toVkCam<float>(cam0);
    for (int i = 0; i < 3; ++i) prm.tPrime[i] = float(tPrime[i]);
    block = paramBlock(&prm, sizeof(prm));
  }
  PcTriangulate pc{addr(radial), addr(points), addr(w), addr(mask), block, radial.width, radial.height};
  dispatch(float64_ ? kTriangulateF64 : kTriangulateF32, pc, radial.width, radial.height);
}

void VulkanBackend::doWarp(const Buffer& dst, const Buffer& src, const Buffer& flow) {
  PcWarp pc{addr(dst), addr(src), addr(flow), dst.width, dst.height, dst.channels, src.width, src.height};
  dispatch(kWarp, pc, dst.width, dst.height);
}

void VulkanBackend::doDownsample(const Buffer& dst, const Buffer& src, float scale) {
  const float sigma = 0.5f * scale;  // resample.cpp decimationSigma
  const int radius = int(std::ceil(2.f * sigma));
  PcDownsample pc{addr(dst), addr(src),  dst.width, dst.height, dst.channels,
                  src.width, src.height, radius,    scale,      sigma};
  dispatch(kDownsample, pc, dst.width, dst.height);
}

void VulkanBackend::doUpsample(const Buffer& dst, const Buffer& src, float scale, float valueScale) {
  PcUpsample pc{addr(dst), addr(src), dst.width, dst.height, dst.channels, src.width, src.height, scale, valueScale};
  dispatch(kUpsample, pc, dst.width, dst.height);
}

// Two passes (normalise_moments.comp, normalise.comp); the taps by device address.
void VulkanBackend::doNormalise(const Buffer& dst, const Buffer& moments, const Buffer& src, const Buffer& mask,
                                const NormaliseParams& p) {
  const vk::NormaliseBlock block = vk::normaliseBlock(p);
  const Addr prm = paramBlock(&block, sizeof(block));
  const int w = src.width, h = src.height;
  dispatch(kNormaliseMoments, vk::PcNormaliseMoments{addr(moments), addr(src), addr(mask), prm, w, h}, w, h);
  dispatch(kNormalise, vk::PcNormalise{addr(dst), addr(moments), addr(src), addr(mask), prm, w, h}, w, h);
}

void VulkanBackend::doStructureTensor(const Buffer& tensor, const Buffer& steps, const Buffer& image,
                                      const Buffer& mask, const TensorParams& p) {
  const int w = image.width, h = image.height;
  Addr smooth = addr(image);
  if (p.sigma > 0.f) {
    const Buffer rows = scratch(0, w, h), blurred = scratch(1, w, h);
    const int radius = int(std::ceil(3.f * p.sigma));
    dispatch(kStructureTensorBlur, PcBlur{addr(rows), addr(image), w, h, radius, 0, p.sigma}, w, h);
    dispatch(kStructureTensorBlur, PcBlur{addr(blurred), addr(rows), w, h, radius, 1, p.sigma}, w, h);
    smooth = addr(blurred);
  }
  dispatch(kStructureTensor, PcTensor{addr(tensor), smooth, w, h, p.beta, p.eta, p.wMin}, w, h);
  dispatch(kStructureTensorSteps, PcSteps{addr(steps), addr(tensor), addr(mask), w, h, p.alpha0, p.alpha1}, w, h);
}

void VulkanBackend::doWarpDerivatives(const DataTermBuffers& data, const Buffer& tangent, const Buffer& i0,
                                      const Buffer& i1, const Buffer& trajectory, const Buffer& w, const Buffer& u,
                                      const Buffer& mask, const Buffer& confidence, float weightFloor) {
  const bool weighted = confidence.id >= 0;
  PcWarpDerivatives pc{addr(data.u0),
                       addr(data.iu),
                       addr(data.iz),
                       addr(tangent),
                       addr(i0),
                       addr(i1),
                       addr(trajectory),
                       addr(w),
                       addr(u),
                       addr(mask),
                       weighted ? addr(confidence) : addr(mask),
                       mask.width,
                       mask.height,
                       weighted ? 1 : 0,
                       weightFloor};
  dispatch(kWarpDerivatives, pc, mask.width, mask.height);
}

void VulkanBackend::doPrimalDual(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                                 const Buffer& steps, const Buffer& mask, const PrimalDualParams& prm) {
  const int w = mask.width, h = mask.height;
  for (const PrimalDualStep& step : prm.schedule) {
    PcDual dual{addr(pd.uBar),   addr(pd.vBar), addr(pd.p), addr(pd.q), addr(tensor), addr(steps), addr(mask), w, h,
                step.sigmaScale, prm.alpha0,    prm.alpha1};
    dispatch(kPrimalDualDual, dual, w, h);
    PcPrimal primal{addr(pd.u),    addr(pd.uBar), addr(pd.v),   addr(pd.vBar), addr(pd.p), addr(pd.q), addr(data.u0),
                    addr(data.iu), addr(data.iz), addr(tensor), addr(steps),   addr(mask), w,          h,
                    step.tauScale, step.theta,    prm.lambda,   prm.alpha0,    prm.alpha1};
    dispatch(kPrimalDualPrimal, primal, w, h);
  }
}

void VulkanBackend::doMedian(const Buffer& dst, const Buffer& src, const Buffer& mask) {
  dispatch(kMedian, PcMedian{addr(dst), addr(src), addr(mask), mask.width, mask.height}, mask.width, mask.height);
}

void VulkanBackend::doAccumulate(const Buffer& u, const Buffer& w, const Buffer& u0, const Buffer& tangent,
                                 const Buffer& mask, float duMax) {
  PcAccumulate pc{addr(u), addr(w), addr(u0), addr(tangent), addr(mask), mask.width, mask.height, duMax};
  dispatch(kAccumulate, pc, mask.width, mask.height);
}

// ---- plane sweep ----

// Mirrors kMaxPlanes in sweep_aggregate.comp (the path costs of two steps in shared memory).
static_assert(kMaxSweepPlanes <= 1024, "sweep_aggregate.comp holds at most 1024 planes");

// The camera, translation and nearest sphere, in the precision of the geometry shaders.
Addr VulkanBackend::sweepParamBlock(const SweepParams& p) {
  auto store = [&](auto prm) {
    using S = std::remove_reference_t<decltype(prm.qMax)>;
    prm.cam = toVkCam<S>(p.cam);
    for (int i = 0; i < 3; ++i) prm.t[i] = S(p.t[i]);
    prm.qMax = S(p.qMax);
    return paramBlock(&prm, sizeof(prm));
  };
  return float64_ ? store(VkSweepParams<double>{}) : store(VkSweepParams<float>{});
}

void VulkanBackend::doSweepWarp(const Buffer& volume, const Buffer& image, const Buffer& mask, const SweepParams& p) {
  PcSweepWarp pc{addr(volume), addr(image), addr(mask), sweepParamBlock(p), volume.width, volume.height, p.planes};
  dispatch(float64_ ? kSweepWarpF64 : kSweepWarpF32, pc, volume.width, volume.height);
}

void VulkanBackend::doSweepCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& mask,
                                const SweepParams& p) {
  // One invocation per (pixel, plane), a row's (x * planes + k) in runs of kGroup^2: the
  // interleaved volume is read and the costs written in consecutive floats.
  const uint64_t rowItems = uint64_t(costs.width) * uint64_t(p.planes);
  const uint64_t groupItems = uint64_t(kGroup) * kGroup;
  PcSweepCost pc{addr(costs),  addr(reference), addr(volume), addr(mask),    costs.width,
                 costs.height, p.planes,        p.radius,     p.flatVariance};
  dispatchGroups(kSweepCost, pc, uint32_t((rowItems + groupItems - 1) / groupItems), uint32_t(costs.height));
}

void VulkanBackend::doSweepAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                                     const SweepParams& p) {
  // The four directions at once, one work group per scanline and direction (+x into
  // `aggregated`, -x, +y, -y into a scratch of three volumes), then their sum in the
  // oracle's order. dispatchGroups puts a full barrier before each dispatch.
  const int w = aggregated.width, h = aggregated.height;
  const Buffer spare = scratch(2, w, h, 3 * p.planes);
  PcSweepAggregate pc{addr(aggregated), addr(spare), addr(costs), addr(mask), w, h, p.planes, p.p1, p.p2};
  dispatchGroups(kSweepAggregate, pc, uint32_t(std::max(w, h)), 4);
  const int64_t count = int64_t(w) * h * p.planes;
  PcSweepCombine sum{addr(aggregated), addr(spare), int32_t(count)};
  dispatchGroups(kSweepCombine, sum, uint32_t((count + 255) / 256), 1);
}

void VulkanBackend::doSweepSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                                  const SweepParams& p) {
  // The plane index becomes an inverse depth in the geometry shaders' precision (double as
  // the oracle where the device has shaderFloat64).
  PcSweepSelect pc{addr(best),         addr(aggregated), addr(costs), addr(mask),
                   sweepParamBlock(p), best.width,       best.height, p.planes};
  dispatch(float64_ ? kSweepSelectF64 : kSweepSelectF32, pc, best.width, best.height);
}

void VulkanBackend::doSweepInitialise(const Buffer& u, const Buffer& w, const Buffer& confidence, const Buffer& best,
                                      const Buffer& other, const Buffer& mask, const SweepParams& p,
                                      const ConsistencyParams& c) {
  // Two dispatches of one shader (dispatch puts a full barrier before each): pass 0 writes
  // the confidence and the consistent pixels' warp, pass 1 reads that confidence to fill
  // occluded pixels from the surface ahead of them.
  const Shader shader = float64_ ? kSweepInitialiseF64 : kSweepInitialiseF32;
  const Addr params = sweepParamBlock(p);
  for (int32_t pass = 0; pass < 2; ++pass) {
    PcSweepInitialise pc{addr(u), addr(w),  addr(confidence), addr(best),         addr(other), addr(mask), params,
                         u.width, u.height, c.tolerancePx,    c.acceptConfidence, pass,        p.planes};
    dispatch(shader, pc, u.width, u.height);
  }
}

}  // namespace cs::vk

// The Vulkan backend's kernels: each Backend kernel as the dispatches of its shaders
// (../shaders), with the parameter blocks and push constants they read. Backend has checked
// every kernel's arguments against its contract (backend.hpp).
#include <algorithm>
#include <cmath>
#include <type_traits>
#include <utility>
#include <vector>

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
  S p[kMaxCameraParams];
  S d[4];
};
static_assert(kMaxCameraParams == 12 && sizeof(VkCam<double>) == 144 && sizeof(VkCam<float>) == 80,
              "VkCam must match the GLSL Cam");

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

// carry_estimate.comp's block: the two grids' cameras and the translation added to the
// motion's (the motion itself is a buffer, read at run time).
template <class S>
struct VkCarryParams {
  VkCam<S> srcCam, dstCam;
  S extraT[3];
};

// temporal_filter.comp's block.
template <class S>
struct VkTemporalParams {
  VkCam<S> cam;
  S tPrime[3];
};

// result_confidence.comp's block.
struct VkConfidenceParams {
  int32_t radius;
  float noise, sigmaPx, residualScale, roundTripPx, roundTripMaxPx, infinityPx, invalidBelow, maxDeviationPx;
  float infinityBoundPx;
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
  for (int i = 0; i < kMaxCameraParams; ++i) out.p[i] = S(c.params[i]);
  out.d[0] = S(c.constants.a);
  out.d[1] = S(c.constants.b);
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
struct PcUpsampleEstimate {
  Addr u, w, coarseU, coarseW, n0, n1, mask;
  int32_t width, height, coarseWidth, coarseHeight, radius;
  float scale, edge;
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
struct PcWarpTail {  // warp_derivatives.comp with CS_WARP_TAIL
  PcWarpDerivatives d;
  Addr uIn;
  float duMax;
  int32_t derive;
};
static_assert(sizeof(PcWarpTail) <= kPushBytes, "push constants exceed the guaranteed 128 bytes");
// primal_dual.comp: the level's block (set 0 the caller's buffers, set 1 the spare set),
// and per dispatch the set read, the iterations and their steps.
constexpr int kMaxPdIterations = 5;  // mirrors kMaxIterations in primal_dual.comp
struct PdLevel {
  Addr u[2], uBar[2], v[2], vBar[2], p[2], q[2];
  Addr u0, iu, iz, tensor, steps, mask;
  Addr uBarFirst, vBarFirst;
  int32_t w, h;
  float lambda, alpha0, alpha1;
};
struct PcPrimalDual {
  Addr level;
  int32_t parity, iterations, first, outside;
  float pad[2];
  float step[kMaxPdIterations][4];  // tauScale, sigmaScale, theta, qAscent
};
enum : int32_t { kCopyOutside = 1, kBarsHome = 2 };  // primal_dual.comp's `outside` bits
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
  int32_t run;
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
  float tolerancePx, acceptConfidence, maxCost;
  int32_t pass, planes;
};
struct PcSweepBandWarp {
  Addr volume, first, image, coarseBest, mask, params;
  int32_t width, height, planes, band, coarseWidth, coarseHeight;
  float coarseScale;
};
struct PcSweepBandCost {
  Addr costs, reference, volume, first, mask;
  int32_t width, height, band, radius;
  float flatVariance;
};
struct PcSweepBandAggregate {
  Addr aggregated, spare, costs, first, mask;
  int32_t width, height, band;
  float p1, p2;
};
struct PcSweepBandSelect {
  Addr best, aggregated, costs, first, mask, params;
  int32_t width, height, planes, band;
};
struct PcCarryEstimate {
  Addr dst, src, guess, motion, mask, params;  // guess: mask when absent
  int32_t width, height, srcWidth, srcHeight, iterations, hasGuess;
};
struct PcTemporalFilter {
  Addr state, u, w, prior, radial, points, confidence, mask, params;  // confidence: mask when absent
  int32_t width, height, hasConfidence;
  float strength, gate, sigmaPx, processPx, minConfidence;
};
struct PcRoundTrip {
  Addr error, w, calibration, reverseW, reverseCalibration, reverseMask, mask;
  int32_t width, height, reverseWidth, reverseHeight;
};
struct PcPlainSupport {
  Addr support, confidence, w, mask, levelImage, levelMask;
  int32_t width, height, fullWidth, fullHeight;
};
struct PcFillPlanes {
  Addr u, w, planeConfidence, labels, planes, mask, params;
  int32_t width, height, labelWidth, labelHeight, planeValues;
};
struct PcFinishResult {
  Addr valid, z, radial, points, disparity, warp, confidence;
  int32_t width, height;
};
struct PcConfidenceTerms {
  Addr terms, image, n0, n1, w, mask;
  int32_t width, height;
};
struct PcResultConfidence {
  Addr confidence, radial, points, terms, w, trajectory, sweepConfidence, roundTripError, planeConfidence, mask, params;
  int32_t width, height, hasSweep, hasRoundTrip, hasPlane;  // absent buffers: mask
};
struct PcPanoramaPlace {
  Addr place, radial, rays;
  int32_t width, height, panoWidth;
  float cx, cy, cz, agreement, maxSplat, parallaxSlack;
};
struct PcPanoramaSplat {
  Addr accum, place, confidence, grey;  // grey: place when absent
  int32_t width, height, panoWidth, pass, hasGrey;
  float minConfidence, agreement, parallaxSlack;
};
struct PcPanoramaResolve {
  Addr range, grey, confidence, accum;
  int32_t width, height;
};
static_assert(sizeof(PcResultConfidence) <= kPushBytes, "push constants exceed the guaranteed 128 bytes");
static_assert(sizeof(PcTemporalFilter) <= kPushBytes, "push constants exceed the guaranteed 128 bytes");
static_assert(sizeof(PcPrimalDual) <= kPushBytes, "push constants exceed the guaranteed 128 bytes");
static_assert(sizeof(PcSweepBandWarp) <= kPushBytes, "push constants exceed the guaranteed 128 bytes");

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

// A camera and t' as VkTriangulateParams in the shader's precision (triangulate.comp and
// fill_planes.comp read the same block).
Addr VulkanBackend::cameraBlock(const CameraParams& cam0, const double tPrime[3], bool inDouble) {
  if (inDouble) {
    VkTriangulateParams<double> prm{};
    prm.cam0 = toVkCam<double>(cam0);
    for (int i = 0; i < 3; ++i) prm.tPrime[i] = tPrime[i];
    return paramBlock(&prm, sizeof(prm));
  }
  VkTriangulateParams<float> prm{};
  prm.cam0 = toVkCam<float>(cam0);
  for (int i = 0; i < 3; ++i) prm.tPrime[i] = float(tPrime[i]);
  return paramBlock(&prm, sizeof(prm));
}

void VulkanBackend::doTriangulate(const Buffer& radial, const Buffer& points, const Buffer& w, const Buffer& mask,
                                  const CameraParams& cam0, const double tPrime[3]) {
  // In double wherever the device has it, whatever the other models use: the least-squares
  // depth of two rays that barely meet (sub-pixel w across the epipolar direction) is a
  // difference far below float's rounding, so float decided "in front" (finite) or not
  // (+inf) unlike the oracle (NVIDIA, 36 of the golden case's pixels). 0.14 ms a frame.
  const bool inDouble = deviceFloat64_;
  PcTriangulate pc{addr(radial), addr(points), addr(w), addr(mask), cameraBlock(cam0, tPrime, inDouble),
                   radial.width, radial.height};
  dispatch(inDouble ? kTriangulateF64 : kTriangulateF32, pc, radial.width, radial.height);
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

void VulkanBackend::doUpsampleEstimate(const Buffer& u, const Buffer& w, const Buffer& coarseU, const Buffer& coarseW,
                                       const Buffer& n0, const Buffer& n1, const Buffer& mask,
                                       const EstimateUpsampleParams& p) {
  PcUpsampleEstimate pc{addr(u), addr(w),  addr(coarseU), addr(coarseW),  addr(n0), addr(n1), addr(mask),
                        u.width, u.height, coarseU.width, coarseU.height, p.radius, p.scale,  p.edge};
  dispatch(kUpsampleEstimate, pc, u.width, u.height);
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

// The warp's tail in one or two dispatches instead of four commands: with the median, the
// median into medianScratch, then warp_tail (warp_derivatives.comp with CS_WARP_TAIL)
// accumulates from it into u (which the median's copy back would have done first) and,
// with nextWarp, makes the next warp's data term; without it, warp_tail accumulates u in
// place. Each of warp_tail's steps reads and writes the pixel's own u, w and tangent only.
void VulkanBackend::doWarpTail(const WarpBuffers& warp, const Buffer& medianScratch, float duMax, bool nextWarp) {
  const bool withMedian = medianScratch.id >= 0;
  if (withMedian) doMedian(medianScratch, warp.u, warp.mask);
  const bool weighted = warp.confidence.id >= 0;
  const Buffer& mask = warp.mask;
  PcWarpTail pc{
      {addr(warp.data.u0), addr(warp.data.iu), addr(warp.data.iz), addr(warp.tangent), addr(warp.i0), addr(warp.i1),
       addr(warp.trajectory), addr(warp.w), addr(warp.u), addr(mask), weighted ? addr(warp.confidence) : addr(mask),
       mask.width, mask.height, weighted ? 1 : 0, warp.weightFloor},
      withMedian ? addr(medianScratch) : addr(warp.u),
      duMax,
      nextWarp ? 1 : 0};
  dispatch(kWarpTail, pc, mask.width, mask.height);
}

void VulkanBackend::doPrimalDual(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                                 const Buffer& steps, const Buffer& mask, const PrimalDualParams& prm) {
  iterate(pd, data, tensor, steps, mask, prm, false);
}

void VulkanBackend::doWarpIterations(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                                     const Buffer& steps, const Buffer& mask, const PrimalDualParams& prm) {
  iterate(pd, data, tensor, steps, mask, prm, true);
}

namespace {

// Work groups the device runs at once, about: a level whose five-iteration tiles fit
// takes five iterations a dispatch, since there the dispatches' latency is what costs
// (backend_cuda/primal_dual.cu measured it); larger ones two or three, where the halo's
// redundant work would cost more. On the H100 with the square tile (T265 pair, N = 30),
// 400 gave 9.12 ms of primal-dual a frame, 200 9.28 and 0 (never five) 10.16.
constexpr uint32_t kConcurrentGroups = 400;

// Work groups a device holds one a multiprocessor, about (an H100 or H200 has 132
// multiprocessors): a level with no more five-iteration groups of a tile than this takes
// the smallest such tile (VulkanBackend::iterate).
constexpr uint32_t kOneGroupPerMultiprocessor = 128;

// primal_dual.comp's cells a work group in each tile (-DCS_NARROW_TILE, the wide default,
// -DCS_SQUARE_TILE).
int pdCellsW(PdTile t) { return t == PdTile::Narrow ? 16 : 32; }
int pdCellsH(PdTile t) { return t == PdTile::Square ? 32 : 16; }

// Work groups of primal_dual.comp over a w x h level at `iterations` a dispatch.
std::pair<uint32_t, uint32_t> pdGroups(int w, int h, int cellsW, int cellsH, int iterations) {
  const int tileW = cellsW + 1 - 2 * iterations, tileH = cellsH + 1 - 2 * iterations;
  return {uint32_t((w + tileW - 1) / tileW), uint32_t((h + tileH - 1) / tileH)};
}

// The iterations of each dispatch: n split into as few parts of at most `most` as make an
// even number (every dispatch swaps the sets, so the result ends in the caller's buffers;
// a single iteration cannot), as even in size as they go.
std::vector<int> pdPlan(int n, int most, int cap) {
  int parts = (n + most - 1) / most;
  if (parts % 2 == 1 && n > 1) parts = parts > 1 && (n + parts - 2) / (parts - 1) <= cap ? parts - 1 : parts + 1;
  std::vector<int> plan(size_t(parts), n / parts);
  for (int i = 0; i < n % parts; ++i) ++plan[size_t(i)];
  return plan;
}

}  // namespace

// Fused iterations (primal_dual.comp), ping-ponging between the caller's buffers (set 0)
// and a spare set; a lone iteration's result is copied back from the spare set.
void VulkanBackend::iterate(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                            const Buffer& steps, const Buffer& mask, const PrimalDualParams& prm,
                            bool barsFromPrimals) {
  const int w = mask.width, h = mask.height, n = int(prm.schedule.size());
  if (n == 0) {  // no iteration to read u, v as the bars: the copies themselves
    if (barsFromPrimals) doCopy(pd.uBar, pd.u), doCopy(pd.vBar, pd.v);
    return;
  }
  const Buffer own[6] = {pd.u, pd.uBar, pd.v, pd.vBar, pd.p, pd.q};
  Buffer spare[6];
  for (int i = 0; i < 6; ++i) spare[i] = scratch(3 + i, w, h, own[i].channels);
  PdLevel level{};
  Addr* sets[6] = {level.u, level.uBar, level.v, level.vBar, level.p, level.q};
  for (int i = 0; i < 6; ++i) sets[i][0] = addr(own[i]), sets[i][1] = addr(spare[i]);
  level.u0 = addr(data.u0), level.iu = addr(data.iu), level.iz = addr(data.iz);
  level.tensor = addr(tensor), level.steps = addr(steps), level.mask = addr(mask);
  level.uBarFirst = barsFromPrimals ? level.u[0] : level.uBar[0];
  level.vBarFirst = barsFromPrimals ? level.v[0] : level.vBar[0];
  level.w = w, level.h = h;
  level.lambda = prm.lambda, level.alpha0 = prm.alpha0, level.alpha1 = prm.alpha1;
  const Addr block = paramBlock(&level, sizeof(level));

  // The square tile (32 x 32 cells) has less halo per written pixel than the wide one
  // (32 x 16: 58 % of its cells written at three iterations against 71 %): on the H100,
  // 9.12 against 12.35 ms of primal-dual a frame at N = 30 (T265 pair). But a level whose
  // five-iteration groups of a smaller tile fit one a multiprocessor takes the smallest
  // such tile (PdTile's order: narrow, wide, square): there a dispatch lasts as long as one
  // group's iterations, which grow with its invocations, and the smaller tile's extra halo
  // runs on multiprocessors that would idle. On the H200 (T265 pair, realtime: 53 x 50
  // narrow, 106 x 100 wide, 212 x 200 square as before) primal-dual took 1.20 ms a frame
  // against 1.55 (CUDA 1.25); at most 64 groups 1.32, 264 1.19.
  PdTile tile = pdTile_;
  bool small = false;
  for (PdTile t : {PdTile::Narrow, PdTile::Wide, PdTile::Square}) {
    if (int(t) > int(pdTile_)) break;
    const std::pair<uint32_t, uint32_t> g = pdGroups(w, h, pdCellsW(t), pdCellsH(t), kMaxPdIterations);
    if (g.first * g.second <= kOneGroupPerMultiprocessor) {
      tile = t, small = true;
      break;
    }
  }
  const bool narrow = tile == PdTile::Narrow;
  const int cellsW = pdCellsW(tile), cellsH = pdCellsH(tile);
  const std::pair<uint32_t, uint32_t> deep = pdGroups(w, h, cellsW, cellsH, kMaxPdIterations);
  const bool fits = small || (!narrow && deep.first * deep.second <= kConcurrentGroups);
  const std::vector<int> plan = pdPlan(n, fits ? kMaxPdIterations : 2, narrow && !small ? 3 : kMaxPdIterations);
  // Masked-out pixels never change: the first dispatch writes them only where the result
  // needs them (into the spare set when the result ends there, the bars into set 0 when
  // they are read from u, v).
  const bool endsSpare = plan.size() % 2 == 1;
  int k = 0;
  for (size_t d = 0; d < plan.size(); ++d) {
    PcPrimalDual pc{};
    pc.level = block;
    pc.parity = int32_t(d % 2);
    pc.iterations = plan[d];
    pc.first = d == 0;
    if (d == 0) pc.outside = endsSpare ? kCopyOutside : barsFromPrimals ? kBarsHome : 0;
    for (int i = 0; i < plan[d]; ++i) {
      const PrimalDualStep& st = prm.schedule[size_t(k + i)];
      const float sigmaQ = st.sigmaScale * 0.5f / prm.alpha0;  // as cpu/primal_dual.cpp
      pc.step[i][0] = st.tauScale, pc.step[i][1] = st.sigmaScale, pc.step[i][2] = st.theta;
      pc.step[i][3] = sigmaQ * prm.alpha0;
    }
    const std::pair<uint32_t, uint32_t> groups = pdGroups(w, h, cellsW, cellsH, plan[d]);
    const Shader shader = tile == PdTile::Square ? kPrimalDualSquare : narrow ? kPrimalDualNarrow : kPrimalDual;
    dispatchGroups(shader, pc, groups.first, groups.second);
    k += plan[d];
  }
  if (endsSpare) {  // six independent copies behind one barrier
    VkCommandBuffer cb = recorder();
    barrier(cb, Cmd::Transfer);
    for (int i = 0; i < 6; ++i) recordCopy(cb, own[i], spare[i]);
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
static_assert(kMaxSweepPlanes <= 512, "sweep_aggregate.comp holds at most 512 planes");
// The floats a work group of sweep_combine.comp adds: 256 invocations of four each.
constexpr int64_t kSweepCombineFloats = 1024;

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
  // A work group per kSweepWarpPixels pixels of a row, its invocations over their planes.
  constexpr int kSweepWarpPixels = 32;  // mirrors kPixels in sweep_warp.comp
  PcSweepWarp pc{addr(volume), addr(image), addr(mask), sweepParamBlock(p), volume.width, volume.height, p.planes};
  dispatchGroups(float64_ ? kSweepWarpF64 : kSweepWarpF32, pc,
                 uint32_t((volume.width + kSweepWarpPixels - 1) / kSweepWarpPixels), uint32_t(volume.height));
}

void VulkanBackend::doSweepCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& mask,
                                const SweepParams& p) {
  // One invocation per plane of a run of `run` pixels of a row, walking the run
  // (sweep_cost.comp): 32 pixels (as backend_cuda) spend 2r / 32 on each run's first
  // columns and still give ~7 x 10^5 invocations at the sweep's level 1; at least two windows.
  const int64_t w = costs.width, h = costs.height, planes = p.planes;
  const int64_t run = std::min(w, std::max<int64_t>(32, 2 * (2 * int64_t(p.radius) + 1)));
  const int64_t rowItems = (w + run - 1) / run * planes;
  PcSweepCost pc{addr(costs), addr(reference), addr(volume), addr(mask),     int32_t(w),
                 int32_t(h),  p.planes,        p.radius,     p.flatVariance, int32_t(run)};
  dispatchGroups(kSweepCost, pc, uint32_t((rowItems + 255) / 256), uint32_t(h));
}

void VulkanBackend::doSweepAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                                     const SweepParams& p) {
  // The four directions at once (+x into `aggregated`, -x, +y, -y into a scratch of
  // three volumes), then their sum in the oracle's order. A scanline per subgroup where
  // the device has subgroup arithmetic and shuffles and a lane holds at most 8 planes (the
  // variant of J = ceil(planes / subgroup size) planes a lane; a work group per scanline
  // and direction covers every line whatever the subgroup size, the groups past the last
  // line return at once, and a device whose subgroups are not the size it reports walks
  // with whole groups), else a work group per scanline. dispatchGroups puts a full
  // barrier before each dispatch.
  static_assert(kSweepAggregateJ8 == kSweepAggregateJ1 + 7, "SHADER_VARIANTS lists sweep_aggregate_j1 .. j8 in order");
  constexpr uint32_t kSweepAggregateGroup = 64;  // mirrors kGroupSize in sweep_aggregate.comp with CS_J
  const int w = aggregated.width, h = aggregated.height;
  const Buffer spare = scratch(2, w, h, 3 * p.planes);
  PcSweepAggregate pc{addr(aggregated), addr(spare), addr(costs), addr(mask), w, h, p.planes, p.p1, p.p2};
  const uint32_t lines = uint32_t(std::max(w, h)), S = subgroupSize_;
  const uint32_t J = (uint32_t(p.planes) + S - 1) / S;
  const bool subgroupWalk =
      subgroupArithmetic_ && J >= 1 && J <= 8 && S <= kSweepAggregateGroup && kSweepAggregateGroup % S == 0;
  dispatchGroups(subgroupWalk ? Shader(kSweepAggregateJ1 + int(J) - 1) : kSweepAggregate, pc, lines, 4);
  const int64_t count = int64_t(w) * h * p.planes;
  PcSweepCombine sum{addr(aggregated), addr(spare), int32_t(count)};
  dispatchGroups(kSweepCombine, sum, uint32_t((count + kSweepCombineFloats - 1) / kSweepCombineFloats), 1);
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
                         u.width, u.height, c.tolerancePx,    c.acceptConfidence, c.maxCost,   pass,       p.planes};
    dispatch(shader, pc, u.width, u.height);
  }
}

// ---- the band sweep ----

// Mirrors kMaxBand in sweep_band_aggregate.comp (a band's hypotheses on one invocation each).
static_assert(kMaxSweepBand <= 32, "sweep_band_aggregate.comp walks a band with 32 invocations");
static_assert(kBandMargin == 2, "sweep_band_warp.comp mirrors kBandMargin");

void VulkanBackend::doSweepBandWarp(const Buffer& volume, const Buffer& first, const Buffer& image,
                                    const Buffer& coarseBest, const Buffer& mask, const SweepParams& p,
                                    float coarseScale) {
  // As doSweepWarp: a work group per kSweepBandWarpPixels pixels of a row, its invocations
  // over their band channels.
  constexpr int kSweepBandWarpPixels = 32;  // mirrors kPixels in sweep_band_warp.comp
  PcSweepBandWarp pc{addr(volume),       addr(first),       addr(image),   addr(coarseBest), addr(mask),
                     sweepParamBlock(p), volume.width,      volume.height, p.planes,         p.band,
                     coarseBest.width,   coarseBest.height, coarseScale};
  dispatchGroups(float64_ ? kSweepBandWarpF64 : kSweepBandWarpF32, pc,
                 uint32_t((volume.width + kSweepBandWarpPixels - 1) / kSweepBandWarpPixels), uint32_t(volume.height));
}

void VulkanBackend::doSweepBandCost(const Buffer& costs, const Buffer& reference, const Buffer& volume,
                                    const Buffer& first, const Buffer& mask, const SweepParams& p) {
  // One invocation per channel of a pixel, each summing its window (sweep_band_cost.comp).
  const int64_t rowItems = int64_t(costs.width) * p.band;
  PcSweepBandCost pc{addr(costs), addr(reference), addr(volume), addr(first), addr(mask),
                     costs.width, costs.height,    p.band,       p.radius,    p.flatVariance};
  dispatchGroups(kSweepBandCost, pc, uint32_t((rowItems + 255) / 256), uint32_t(costs.height));
}

void VulkanBackend::doSweepBandAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& first,
                                         const Buffer& mask, const SweepParams& p) {
  // As doSweepAggregate: the four directions at once (+x into `aggregated`, the others
  // into a scratch of three band volumes), then sweep_combine.comp's sum in the oracle's
  // order. A line per subgroup (a work group of one) where the device has subgroup
  // arithmetic and shuffles and subgroups of 32, 16, 8 or 4 (the variant of 32 / size
  // hypotheses a lane), else kSweepBandAggregateLines lines per work group of 32.
  constexpr int kSweepBandAggregateLines = 1;  // mirrors kLines in sweep_band_aggregate.comp
  const int w = aggregated.width, h = aggregated.height;
  const Buffer spare = scratch(2, w, h, 3 * p.band);
  PcSweepBandAggregate pc{addr(aggregated), addr(spare), addr(costs), addr(first), addr(mask), w, h,
                          p.band,           p.p1,        p.p2};
  const int lines = std::max(w, h);
  Shader walk = kSweepBandAggregate;
  if (subgroupArithmetic_) {
    switch (subgroupSize_) {
      case 32:
        walk = kSweepBandAggregateJ1;
        break;
      case 16:
        walk = kSweepBandAggregateJ2;
        break;
      case 8:
        walk = kSweepBandAggregateJ4;
        break;
      case 4:
        walk = kSweepBandAggregateJ8;
        break;
      default:
        break;
    }
  }
  if (walk != kSweepBandAggregate)
    dispatchGroups(walk, pc, uint32_t(lines), 4);
  else
    dispatchGroups(walk, pc, uint32_t((lines + kSweepBandAggregateLines - 1) / kSweepBandAggregateLines), 4);
  const int64_t count = int64_t(w) * h * p.band;
  PcSweepCombine sum{addr(aggregated), addr(spare), int32_t(count)};
  dispatchGroups(kSweepCombine, sum, uint32_t((count + kSweepCombineFloats - 1) / kSweepCombineFloats), 1);
}

void VulkanBackend::doSweepBandSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs,
                                      const Buffer& first, const Buffer& mask, const SweepParams& p) {
  PcSweepBandSelect pc{addr(best),         addr(aggregated), addr(costs), addr(first), addr(mask),
                       sweepParamBlock(p), best.width,       best.height, p.planes,    p.band};
  dispatch(float64_ ? kSweepBandSelectF64 : kSweepBandSelectF32, pc, best.width, best.height);
}

// ---- sequences ----

// The motion stays in its buffer (uploaded each frame outside the recorded frame): only the
// cameras and extraT, constant over a sequence, are in the parameter block.
void VulkanBackend::doCarryEstimate(const Buffer& dst, const Buffer& src, const Buffer& guess, const Buffer& motion,
                                    const Buffer& mask, const CarryParams& p) {
  auto store = [&](auto prm) {
    using S = std::remove_reference_t<decltype(prm.extraT[0])>;
    prm.srcCam = toVkCam<S>(p.srcCam);
    prm.dstCam = toVkCam<S>(p.dstCam);
    for (int i = 0; i < 3; ++i) prm.extraT[i] = S(p.extraT[i]);
    return paramBlock(&prm, sizeof(prm));
  };
  const Addr block = float64_ ? store(VkCarryParams<double>{}) : store(VkCarryParams<float>{});
  const bool hasGuess = guess.id >= 0;
  PcCarryEstimate pc{addr(dst),    addr(src),    addr(hasGuess ? guess : mask),
                     addr(motion), addr(mask),   block,
                     dst.width,    dst.height,   src.width,
                     src.height,   p.iterations, hasGuess ? 1 : 0};
  dispatch(float64_ ? kCarryEstimateF64 : kCarryEstimateF32, pc, dst.width, dst.height);
}

void VulkanBackend::doTemporalFilter(const Buffer& state, const Buffer& u, const Buffer& w, const Buffer& prior,
                                     const Buffer& radial, const Buffer& points, const Buffer& confidence,
                                     const Buffer& mask, const TemporalParams& p) {
  auto store = [&](auto prm) {
    using S = std::remove_reference_t<decltype(prm.tPrime[0])>;
    prm.cam = toVkCam<S>(p.cam);
    for (int i = 0; i < 3; ++i) prm.tPrime[i] = S(p.tPrime[i]);
    return paramBlock(&prm, sizeof(prm));
  };
  const Addr block = float64_ ? store(VkTemporalParams<double>{}) : store(VkTemporalParams<float>{});
  const bool weighted = confidence.id >= 0;
  PcTemporalFilter pc{addr(state),
                      addr(u),
                      addr(w),
                      addr(prior),
                      addr(radial),
                      addr(points),
                      addr(weighted ? confidence : mask),
                      addr(mask),
                      block,
                      state.width,
                      state.height,
                      weighted ? 1 : 0,
                      p.strength,
                      p.gate,
                      p.sigmaPx,
                      p.processPx,
                      p.minConfidence};
  dispatch(float64_ ? kTemporalFilterF64 : kTemporalFilterF32, pc, state.width, state.height);
}

// ---- the result's confidence ----

void VulkanBackend::doFinishResult(const Buffer& valid, const Buffer& z, const Buffer& radial, const Buffer& points,
                                   const Buffer& disparity, const Buffer& warp, const Buffer& confidence) {
  PcFinishResult pc{addr(valid), addr(z),          addr(radial), addr(points), addr(disparity),
                    addr(warp),  addr(confidence), radial.width, radial.height};
  dispatch(kFinishResult, pc, radial.width, radial.height);
}

void VulkanBackend::doPlainSupport(const Buffer& support, const Buffer& confidence, const Buffer& w, const Buffer& mask,
                                   const Buffer& levelImage, const Buffer& levelMask) {
  PcPlainSupport pc{addr(support),   addr(confidence), addr(w),        addr(mask), addr(levelImage),
                    addr(levelMask), support.width,    support.height, mask.width, mask.height};
  dispatch(kPlainSupport, pc, support.width, support.height);
}

void VulkanBackend::doFillPlanes(const Buffer& u, const Buffer& w, const Buffer& planeConfidence, const Buffer& labels,
                                 const Buffer& planes, const Buffer& mask, const CameraParams& cam0,
                                 const double tPrime[3]) {
  // In double where the device has it, as triangulate: the same camera equations.
  const bool inDouble = deviceFloat64_;
  const Addr block = cameraBlock(cam0, tPrime, inDouble);
  PcFillPlanes pc{addr(u), addr(w),  addr(planeConfidence), addr(labels),  addr(planes),           addr(mask), block,
                  u.width, u.height, labels.width,          labels.height, int32_t(planes.count())};
  dispatch(inDouble ? kFillPlanesF64 : kFillPlanesF32, pc, u.width, u.height);
}

void VulkanBackend::doRoundTrip(const Buffer& error, const Buffer& w, const Buffer& calibration, const Buffer& reverseW,
                                const Buffer& reverseCalibration, const Buffer& reverseMask, const Buffer& mask) {
  PcRoundTrip pc{addr(error),       addr(w),    addr(calibration), addr(reverseW), addr(reverseCalibration),
                 addr(reverseMask), addr(mask), error.width,       error.height,   reverseMask.width,
                 reverseMask.height};
  dispatch(kRoundTrip, pc, error.width, error.height);
}

void VulkanBackend::doResultConfidence(const Buffer& confidence, const Buffer& radial, const Buffer& points,
                                       const Buffer& image, const Buffer& n0, const Buffer& n1, const Buffer& w,
                                       const Buffer& trajectory, const Buffer& sweepConfidence,
                                       const Buffer& roundTripError, const Buffer& planeConfidence, const Buffer& mask,
                                       const ConfidenceParams& p) {
  VkConfidenceParams prm{p.radius,         p.noise,      p.sigmaPx,      p.residualScale,  p.roundTripPx,
                         p.roundTripMaxPx, p.infinityPx, p.invalidBelow, p.maxDeviationPx, p.infinityBoundPx};
  const bool hasSweep = sweepConfidence.id >= 0, hasTrip = roundTripError.id >= 0, hasPlane = planeConfidence.id >= 0;
  const int width = confidence.width, height = confidence.height;
  // Two passes, as on CUDA: each pixel's terms once, then the windows' sums of them.
  const Buffer terms = scratch(kConfidenceTermsScratch, width, height, 4);
  dispatch(kResultConfidenceTerms,
           PcConfidenceTerms{addr(terms), addr(image), addr(n0), addr(n1), addr(w), addr(mask), width, height}, width,
           height);
  PcResultConfidence pc{addr(confidence),
                        addr(radial),
                        addr(points),
                        addr(terms),
                        addr(w),
                        addr(trajectory),
                        addr(hasSweep ? sweepConfidence : mask),
                        addr(hasTrip ? roundTripError : mask),
                        addr(hasPlane ? planeConfidence : mask),
                        addr(mask),
                        paramBlock(&prm, sizeof prm),
                        confidence.width,
                        confidence.height,
                        hasSweep ? 1 : 0,
                        hasTrip ? 1 : 0,
                        hasPlane ? 1 : 0};
  dispatch(kResultConfidence, pc, width, height);
}

// ---- a rig's panorama ----

void VulkanBackend::doPanoramaPlace(const Buffer& place, const Buffer& radial, const Buffer& rays,
                                    const PanoramaParams& p) {
  PcPanoramaPlace pc{addr(place), addr(radial), addr(rays),  radial.width,       radial.height,     p.width,
                     p.centre[0], p.centre[1],  p.centre[2], kPanoramaAgreement, kPanoramaMaxSplat, p.parallaxSlack};
  dispatch(kPanoramaPlace, pc, radial.width, radial.height);
}

void VulkanBackend::doPanoramaSplat(const Buffer& accum, const Buffer& place, const Buffer& confidence,
                                    const Buffer& grey, const PanoramaParams& p) {
  const bool hasGrey = grey.id >= 0;
  PcPanoramaSplat pc{addr(accum),
                     addr(place),
                     addr(confidence),
                     addr(hasGrey ? grey : place),
                     place.width,
                     place.height,
                     p.width,
                     p.pass,
                     hasGrey ? 1 : 0,
                     p.minConfidence,
                     kPanoramaAgreement,
                     p.parallaxSlack};
  const Shader s = subgroupBallot_ ? (atomicFloatAdd_ ? kPanoramaSplatSubgroupAtomic : kPanoramaSplatSubgroup)
                                   : (atomicFloatAdd_ ? kPanoramaSplatAtomic : kPanoramaSplat);
  dispatch(s, pc, place.width, place.height);
}

void VulkanBackend::doPanoramaResolve(const Buffer& range, const Buffer& grey, const Buffer& confidence,
                                      const Buffer& accum) {
  PcPanoramaResolve pc{addr(range), addr(grey), addr(confidence), addr(accum), accum.width, accum.height};
  dispatch(kPanoramaResolve, pc, accum.width, accum.height);
}

}  // namespace cs::vk

// The Backend interface's contracts (backend.hpp), checked once above every backend: each
// public kernel checks its arguments and calls the backend's protected "do" virtual. The
// coarse kernels' default implementations (the fine kernels in their documented order)
// are here too.
#include <algorithm>
#include <cmath>
#include <string>

#include "curvestereo/backend.hpp"
#include "curvestereo/camera_models.hpp"
#include "curvestereo/image.hpp"

namespace cs {

namespace {

std::string shapeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }
std::string shapeText(const Buffer& b) { return shapeText(b.width, b.height) + "x" + std::to_string(b.channels); }

bool knownModel(int model) { return models::paramCount(CameraModel(model)) >= 0; }

}  // namespace

// The checks of one call: fail() throws "<backend> backend: <kernel>: <problem>".
class BackendContract {
 public:
  BackendContract(const Backend& backend, const char* kernel) : backend_(backend), kernel_(kernel) {}

  [[noreturn]] void fail(const std::string& problem) const {
    throw Error(backend_.name() + " backend: " + kernel_ + ": " + problem);
  }

  // `b` was created by this backend, is used no larger than created, and has `channels`
  // (0: any).
  const BackendContract& buffer(const Buffer& b, const char* what, int channels = 0) const {
    const std::vector<Buffer>& created = backend_.created_;
    if (b.id < 0 || size_t(b.id) >= created.size() || created[size_t(b.id)].id != b.id)
      fail(std::string(what) + " is not a buffer of this backend (id " + std::to_string(b.id) + ")");
    const Buffer& c = created[size_t(b.id)];
    if (b.width <= 0 || b.height <= 0 || b.channels <= 0 || b.count() > c.count())
      fail(std::string(what) + " (buffer " + std::to_string(b.id) + ") is used as " + shapeText(b) +
           ", larger than it was created (" + shapeText(c) + ")");
    if (channels > 0 && b.channels != channels)
      fail(std::string(what) + " has " + std::to_string(b.channels) + " channel" + (b.channels == 1 ? "" : "s") +
           ", expected " + std::to_string(channels));
    return *this;
  }

  // `b` (checked as by buffer()) has the width and height of `grid`.
  const BackendContract& sameGrid(const Buffer& b, const char* what, int channels, const Buffer& grid,
                                  const char* gridName) const {
    buffer(b, what, channels);
    if (b.width != grid.width || b.height != grid.height)
      fail(std::string(what) + " is " + shapeText(b.width, b.height) + " but " + gridName + " is " +
           shapeText(grid.width, grid.height));
    return *this;
  }

  const BackendContract& require(bool ok, const std::string& problem) const {
    if (!ok) fail(problem);
    return *this;
  }

  // A camera the kernels can evaluate; with `grid`, one of that grid's size.
  const BackendContract& camera(const CameraParams& cam, const char* what, const Buffer* grid = nullptr,
                                const char* gridName = nullptr) const {
    require(knownModel(cam.model), std::string(what) + " has an unknown camera model " + std::to_string(cam.model));
    if (grid && (cam.width != grid->width || cam.height != grid->height))
      fail(std::string(what) + " is " + shapeText(cam.width, cam.height) + " but " + gridName + " is " +
           shapeText(grid->width, grid->height));
    return *this;
  }

  const BackendContract& sweep(const SweepParams& p) const {
    require(p.planes >= 2 && p.planes <= kMaxSweepPlanes,
            "needs 2 to " + std::to_string(kMaxSweepPlanes) + " planes, got " + std::to_string(p.planes));
    require(p.radius >= 0, "needs a window radius >= 0, got " + std::to_string(p.radius));
    return camera(p.cam, "the camera");
  }

  const BackendContract& band(const SweepParams& p) const {
    sweep(p);
    const int most = std::min(p.planes, kMaxSweepBand);
    return require(p.band >= 2 && p.band <= most,
                   "needs a band of 2 to " + std::to_string(most) + " hypotheses, got " + std::to_string(p.band));
  }

  void median(const Buffer& dst, const Buffer& src, const Buffer& mask) const {
    buffer(mask, "mask", 1);
    sameGrid(dst, "dst", 1, mask, "mask").sameGrid(src, "src", 1, mask, "mask");
    require(dst.id != src.id, "dst and src are the same buffer");
  }

  void accumulate(const Buffer& u, const Buffer& w, const Buffer& u0, const Buffer& tangent, const Buffer& mask,
                  float duMax) const {
    buffer(mask, "mask", 1);
    sameGrid(u, "u", 1, mask, "mask").sameGrid(w, "w", 2, mask, "mask").sameGrid(u0, "u0", 1, mask, "mask");
    sameGrid(tangent, "tangent", 2, mask, "mask");
    require(duMax >= 0.f, "duMax must be >= 0, got " + std::to_string(duMax));
  }

  void warpDerivatives(const DataTermBuffers& data, const Buffer& tangent, const Buffer& i0, const Buffer& i1,
                       const Buffer& trajectory, const Buffer& w, const Buffer& u, const Buffer& mask,
                       const Buffer& confidence) const {
    buffer(mask, "mask", 1);
    sameGrid(data.u0, "u0", 1, mask, "mask").sameGrid(data.iu, "iu", 1, mask, "mask");
    sameGrid(data.iz, "iz", 1, mask, "mask").sameGrid(tangent, "tangent", 2, mask, "mask");
    sameGrid(i0, "i0", 1, mask, "mask").sameGrid(i1, "i1", 1, mask, "mask");
    sameGrid(trajectory, "trajectory", 2, mask, "mask").sameGrid(w, "w", 2, mask, "mask");
    sameGrid(u, "u", 1, mask, "mask");
    if (confidence.id >= 0) sameGrid(confidence, "confidence", 1, mask, "mask");
  }

  void primalDual(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor, const Buffer& steps,
                  const Buffer& mask) const {
    buffer(mask, "mask", 1);
    sameGrid(pd.u, "u", 1, mask, "mask").sameGrid(pd.uBar, "uBar", 1, mask, "mask");
    sameGrid(pd.v, "v", 2, mask, "mask").sameGrid(pd.vBar, "vBar", 2, mask, "mask");
    sameGrid(pd.p, "p", 2, mask, "mask").sameGrid(pd.q, "q", 4, mask, "mask");
    sameGrid(data.u0, "u0", 1, mask, "mask").sameGrid(data.iu, "iu", 1, mask, "mask");
    sameGrid(data.iz, "iz", 1, mask, "mask");
    sameGrid(tensor, "tensor", 4, mask, "mask").sameGrid(steps, "steps", 4, mask, "mask");
  }

 private:
  const Backend& backend_;
  const char* kernel_;
};

// --- memory ---

Buffer Backend::create(int width, int height, int channels) {
  if (width <= 0 || height <= 0 || channels <= 0)
    BackendContract(*this, "create")
        .fail("invalid buffer size " + shapeText(width, height) + "x" + std::to_string(channels));
  const Buffer b = doCreate(width, height, channels);
  if (b.id >= 0) {
    if (size_t(b.id) >= created_.size()) created_.resize(size_t(b.id) + 1);
    created_[size_t(b.id)] = b;
  }
  return b;
}

void Backend::upload(const Buffer& dst, const float* host, bool* finite) {
  BackendContract(*this, "upload").buffer(dst, "dst");
  doUpload(dst, host, finite);
}

void Backend::uploadBytes(const Buffer& dst, const uint8_t* host) {
  BackendContract(*this, "uploadBytes").buffer(dst, "dst");
  doUploadBytes(dst, host);
}

void Backend::download(const Buffer& src, float* host) {
  BackendContract(*this, "download").buffer(src, "src");
  doDownload(src, host);
}

void Backend::downloadAll(const std::vector<Download>& downloads) {
  const BackendContract c(*this, "downloadAll");
  for (const Download& d : downloads) c.buffer(d.src, "src");
  doDownloadAll(downloads);
}

void Backend::doDownloadAll(const std::vector<Download>& downloads) {
  for (const Download& d : downloads) doDownload(d.src, d.host);
}

void Backend::fill(const Buffer& dst, float value) {
  BackendContract(*this, "fill").buffer(dst, "dst");
  doFill(dst, value);
}

void Backend::copy(const Buffer& dst, const Buffer& src) {
  const BackendContract c(*this, "copy");
  c.buffer(dst, "dst").buffer(src, "src");
  c.require(dst.count() == src.count(), "dst (" + shapeText(dst) + ") and src (" + shapeText(src) + ") differ in size");
  doCopy(dst, src);
}

// --- kernels ---

void Backend::fields(const Buffer& mask, const Buffer& calibration, const Buffer& trajectory,
                     const FieldsParams& params) {
  const BackendContract c(*this, "fields");
  c.buffer(mask, "mask", 1);
  c.sameGrid(calibration, "calibration", 2, mask, "mask").sameGrid(trajectory, "trajectory", 2, mask, "mask");
  c.camera(params.cam0, "cam0", &mask, "mask").camera(params.cam1, "cam1");
  doFields(mask, calibration, trajectory, params);
}

void Backend::warp(const Buffer& dst, const Buffer& src, const Buffer& flow) {
  const BackendContract c(*this, "warp");
  c.buffer(dst, "dst").buffer(src, "src", dst.channels).sameGrid(flow, "flow", 2, dst, "dst");
  doWarp(dst, src, flow);
}

void Backend::downsample(const Buffer& dst, const Buffer& src, float scale) {
  const BackendContract c(*this, "downsample");
  c.buffer(dst, "dst").buffer(src, "src", dst.channels);
  c.require(std::isfinite(scale) && scale > 0.f, "scale must be positive, got " + std::to_string(scale));
  doDownsample(dst, src, scale);
}

void Backend::upsample(const Buffer& dst, const Buffer& src, float scale, float valueScale) {
  const BackendContract c(*this, "upsample");
  c.buffer(dst, "dst").buffer(src, "src", dst.channels);
  c.require(std::isfinite(scale) && scale > 0.f, "scale must be positive, got " + std::to_string(scale));
  doUpsample(dst, src, scale, valueScale);
}

void Backend::upsampleEstimate(const Buffer& u, const Buffer& w, const Buffer& coarseU, const Buffer& coarseW,
                               const Buffer& n0, const Buffer& n1, const Buffer& mask,
                               const EstimateUpsampleParams& p) {
  const BackendContract c(*this, "upsampleEstimate");
  c.buffer(mask, "mask", 1).sameGrid(u, "u", 1, mask, "mask").sameGrid(w, "w", 2, mask, "mask");
  c.sameGrid(n0, "n0", 1, mask, "mask").sameGrid(n1, "n1", 1, mask, "mask");
  c.buffer(coarseU, "coarseU", 1).sameGrid(coarseW, "coarseW", 2, coarseU, "coarseU");
  c.require(coarseU.width >= 2 && coarseU.height >= 2,
            "the coarse grid must be at least 2x2, got " + shapeText(coarseU.width, coarseU.height));
  c.require(std::isfinite(p.scale) && p.scale > 1.f, "scale must be above 1, got " + std::to_string(p.scale));
  c.require(std::isfinite(p.edge) && p.edge > 0.f, "edge must be positive, got " + std::to_string(p.edge));
  c.require(p.radius >= 0 && p.radius <= kMaxUpsampleRadius,
            "radius " + std::to_string(p.radius) + " outside [0, " + std::to_string(kMaxUpsampleRadius) + "]");
  doUpsampleEstimate(u, w, coarseU, coarseW, n0, n1, mask, p);
}

void Backend::normalise(const Buffer& dst, const Buffer& moments, const Buffer& src, const Buffer& mask,
                        const NormaliseParams& params) {
  const BackendContract c(*this, "normalise");
  c.buffer(src, "src", 1).sameGrid(dst, "dst", 1, src, "src");
  c.sameGrid(moments, "moments", 3, src, "src").sameGrid(mask, "mask", 1, src, "src");
  c.require(params.radius >= 0 && params.radius <= kMaxNormaliseRadius,
            "radius " + std::to_string(params.radius) + " outside [0, " + std::to_string(kMaxNormaliseRadius) + "]");
  doNormalise(dst, moments, src, mask, params);
}

void Backend::structureTensor(const Buffer& tensor, const Buffer& steps, const Buffer& image, const Buffer& mask,
                              const TensorParams& params) {
  const BackendContract c(*this, "structureTensor");
  c.buffer(image, "image", 1).sameGrid(mask, "mask", 1, image, "image");
  c.sameGrid(tensor, "tensor", 4, image, "image").sameGrid(steps, "steps", 4, image, "image");
  c.require(params.sigma >= 0.f && std::ceil(3.f * params.sigma) <= float(kMaxTensorRadius),
            "smoothing sigma " + std::to_string(params.sigma) + " outside [0, " + std::to_string(kMaxTensorRadius / 3) +
                "] px");
  doStructureTensor(tensor, steps, image, mask, params);
}

void Backend::warpDerivatives(const DataTermBuffers& data, const Buffer& tangent, const Buffer& i0, const Buffer& i1,
                              const Buffer& trajectory, const Buffer& w, const Buffer& u, const Buffer& mask,
                              const Buffer& confidence, float weightFloor) {
  BackendContract(*this, "warpDerivatives").warpDerivatives(data, tangent, i0, i1, trajectory, w, u, mask, confidence);
  doWarpDerivatives(data, tangent, i0, i1, trajectory, w, u, mask, confidence, weightFloor);
}

void Backend::primalDual(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                         const Buffer& steps, const Buffer& mask, const PrimalDualParams& params) {
  BackendContract(*this, "primalDual").primalDual(pd, data, tensor, steps, mask);
  doPrimalDual(pd, data, tensor, steps, mask, params);
}

void Backend::median(const Buffer& dst, const Buffer& src, const Buffer& mask) {
  BackendContract(*this, "median").median(dst, src, mask);
  doMedian(dst, src, mask);
}

void Backend::accumulate(const Buffer& u, const Buffer& w, const Buffer& u0, const Buffer& tangent, const Buffer& mask,
                         float duMax) {
  BackendContract(*this, "accumulate").accumulate(u, w, u0, tangent, mask, duMax);
  doAccumulate(u, w, u0, tangent, mask, duMax);
}

// --- coarse kernels ---

void Backend::warpIterations(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                             const Buffer& steps, const Buffer& mask, const PrimalDualParams& params) {
  BackendContract(*this, "warpIterations").primalDual(pd, data, tensor, steps, mask);
  doWarpIterations(pd, data, tensor, steps, mask, params);
}

void Backend::doWarpIterations(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                               const Buffer& steps, const Buffer& mask, const PrimalDualParams& params) {
  copy(pd.uBar, pd.u);
  copy(pd.vBar, pd.v);
  primalDual(pd, data, tensor, steps, mask, params);
}

void Backend::warpTail(const WarpBuffers& warp, const Buffer& medianScratch, float duMax, bool nextWarp) {
  const BackendContract c(*this, "warpTail");
  if (medianScratch.id >= 0) c.median(medianScratch, warp.u, warp.mask);
  c.accumulate(warp.u, warp.w, warp.data.u0, warp.tangent, warp.mask, duMax);
  if (nextWarp)
    c.warpDerivatives(warp.data, warp.tangent, warp.i0, warp.i1, warp.trajectory, warp.w, warp.u, warp.mask,
                      warp.confidence);
  doWarpTail(warp, medianScratch, duMax, nextWarp);
}

void Backend::doWarpTail(const WarpBuffers& warp, const Buffer& medianScratch, float duMax, bool nextWarp) {
  if (medianScratch.id >= 0) {
    median(medianScratch, warp.u, warp.mask);
    copy(warp.u, medianScratch);
  }
  accumulate(warp.u, warp.w, warp.data.u0, warp.tangent, warp.mask, duMax);
  if (nextWarp)
    warpDerivatives(warp.data, warp.tangent, warp.i0, warp.i1, warp.trajectory, warp.w, warp.u, warp.mask,
                    warp.confidence, warp.weightFloor);
}

// --- plane sweep ---

void Backend::sweepWarp(const Buffer& volume, const Buffer& image, const Buffer& mask, const SweepParams& p) {
  const BackendContract c(*this, "sweepWarp");
  c.sweep(p);
  c.buffer(mask, "mask", 1).sameGrid(volume, "volume", p.planes, mask, "mask");
  c.sameGrid(image, "image", 1, mask, "mask");
  doSweepWarp(volume, image, mask, p);
}

void Backend::sweepCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& mask,
                        const SweepParams& p) {
  const BackendContract c(*this, "sweepCost");
  c.sweep(p);
  c.buffer(mask, "mask", 1).sameGrid(costs, "costs", p.planes, mask, "mask");
  c.sameGrid(reference, "reference", 1, mask, "mask").sameGrid(volume, "volume", p.planes, mask, "mask");
  doSweepCost(costs, reference, volume, mask, p);
}

void Backend::sweepAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& mask, const SweepParams& p) {
  const BackendContract c(*this, "sweepAggregate");
  c.sweep(p);
  c.buffer(mask, "mask", 1).sameGrid(aggregated, "aggregated", p.planes, mask, "mask");
  c.sameGrid(costs, "costs", p.planes, mask, "mask");
  c.require(aggregated.id != costs.id, "aggregated and costs are the same buffer");
  doSweepAggregate(aggregated, costs, mask, p);
}

void Backend::sweepSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                          const SweepParams& p) {
  const BackendContract c(*this, "sweepSelect");
  c.sweep(p);
  c.buffer(mask, "mask", 1).sameGrid(best, "best", 2, mask, "mask");
  c.sameGrid(aggregated, "aggregated", p.planes, mask, "mask").sameGrid(costs, "costs", p.planes, mask, "mask");
  doSweepSelect(best, aggregated, costs, mask, p);
}

void Backend::sweepInitialise(const Buffer& u, const Buffer& w, const Buffer& confidence, const Buffer& best,
                              const Buffer& other, const Buffer& mask, const SweepParams& p,
                              const ConsistencyParams& consistency) {
  const BackendContract c(*this, "sweepInitialise");
  c.sweep(p);
  c.buffer(mask, "mask", 1).sameGrid(u, "u", 1, mask, "mask").sameGrid(w, "w", 2, mask, "mask");
  c.sameGrid(confidence, "confidence", 1, mask, "mask").sameGrid(best, "best", 2, mask, "mask");
  c.sameGrid(other, "other", 2, mask, "mask");
  doSweepInitialise(u, w, confidence, best, other, mask, p, consistency);
}

void Backend::sweepBandWarp(const Buffer& volume, const Buffer& first, const Buffer& image, const Buffer& coarseBest,
                            const Buffer& mask, const SweepParams& p, float coarseScale) {
  const BackendContract c(*this, "sweepBandWarp");
  c.band(p);
  c.buffer(mask, "mask", 1).sameGrid(volume, "volume", p.band, mask, "mask");
  c.sameGrid(first, "first", 1, mask, "mask").sameGrid(image, "image", 1, mask, "mask");
  c.buffer(coarseBest, "coarseBest", 2);
  c.require(coarseScale > 0.f && coarseScale <= 1.f,
            "needs a coarse scale in (0, 1], got " + std::to_string(coarseScale));
  doSweepBandWarp(volume, first, image, coarseBest, mask, p, coarseScale);
}

void Backend::sweepBandCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& first,
                            const Buffer& mask, const SweepParams& p) {
  const BackendContract c(*this, "sweepBandCost");
  c.band(p);
  c.buffer(mask, "mask", 1).sameGrid(costs, "costs", p.band, mask, "mask");
  c.sameGrid(reference, "reference", 1, mask, "mask").sameGrid(volume, "volume", p.band, mask, "mask");
  c.sameGrid(first, "first", 1, mask, "mask");
  doSweepBandCost(costs, reference, volume, first, mask, p);
}

void Backend::sweepBandAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& first, const Buffer& mask,
                                 const SweepParams& p) {
  const BackendContract c(*this, "sweepBandAggregate");
  c.band(p);
  c.buffer(mask, "mask", 1).sameGrid(aggregated, "aggregated", p.band, mask, "mask");
  c.sameGrid(costs, "costs", p.band, mask, "mask").sameGrid(first, "first", 1, mask, "mask");
  c.require(aggregated.id != costs.id, "aggregated and costs are the same buffer");
  doSweepBandAggregate(aggregated, costs, first, mask, p);
}

void Backend::sweepBandSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& first,
                              const Buffer& mask, const SweepParams& p) {
  const BackendContract c(*this, "sweepBandSelect");
  c.band(p);
  c.buffer(mask, "mask", 1).sameGrid(best, "best", 2, mask, "mask");
  c.sameGrid(aggregated, "aggregated", p.band, mask, "mask").sameGrid(costs, "costs", p.band, mask, "mask");
  c.sameGrid(first, "first", 1, mask, "mask");
  doSweepBandSelect(best, aggregated, costs, first, mask, p);
}

void Backend::triangulate(const Buffer& radial, const Buffer& points, const Buffer& w, const Buffer& mask,
                          const CameraParams& cam0, const double tPrime[3]) {
  const BackendContract c(*this, "triangulate");
  c.buffer(mask, "mask", 1).sameGrid(radial, "radial", 1, mask, "mask");
  c.sameGrid(points, "points", 3, mask, "mask").sameGrid(w, "w", 2, mask, "mask");
  c.camera(cam0, "cam0", &mask, "mask");
  doTriangulate(radial, points, w, mask, cam0, tPrime);
}

}  // namespace cs

namespace cs {

void Backend::carryEstimate(const Buffer& dst, const Buffer& src, const Buffer& guess, const Buffer& motion,
                            const Buffer& mask, const CarryParams& p) {
  const BackendContract c(*this, "carryEstimate");
  c.buffer(mask, "mask", 1).sameGrid(dst, "dst", 2, mask, "mask");
  c.buffer(src, "src", 2).buffer(motion, "motion", 1);
  if (guess.id >= 0) c.sameGrid(guess, "guess", 1, mask, "mask");
  c.require(motion.width == kMotionFloats && motion.height == 1,
            "motion is " + shapeText(motion) + ", expected " + std::to_string(kMotionFloats) + "x1x1");
  c.camera(p.dstCam, "dstCam", &mask, "mask").camera(p.srcCam, "srcCam", &src, "src");
  c.require(p.iterations >= 1, "needs at least one iteration, got " + std::to_string(p.iterations));
  c.require(dst.id != src.id, "dst and src are the same buffer");
  doCarryEstimate(dst, src, guess, motion, mask, p);
}

void Backend::temporalFilter(const Buffer& state, const Buffer& u, const Buffer& w, const Buffer& prior,
                             const Buffer& radial, const Buffer& points, const Buffer& confidence, const Buffer& mask,
                             const TemporalParams& p) {
  const BackendContract c(*this, "temporalFilter");
  c.buffer(mask, "mask", 1).sameGrid(state, "state", 2, mask, "mask").sameGrid(prior, "prior", 2, mask, "mask");
  c.sameGrid(u, "u", 1, mask, "mask").sameGrid(w, "w", 2, mask, "mask").sameGrid(radial, "radial", 1, mask, "mask");
  c.sameGrid(points, "points", 3, mask, "mask");
  if (confidence.id >= 0) c.sameGrid(confidence, "confidence", 1, mask, "mask");
  c.camera(p.cam, "cam", &mask, "mask");
  c.require(state.id != prior.id, "state and prior are the same buffer");
  c.require(p.strength >= 0.f && p.strength < 1.f, "strength must be in [0, 1), got " + std::to_string(p.strength));
  c.require(p.gate > 0.f && p.sigmaPx > 0.f && p.processPx >= 0.f, "gate and sigmaPx must be > 0 and processPx >= 0");
  c.require(p.minConfidence > 0.f && p.minConfidence <= 1.f,
            "minConfidence must be in (0, 1], got " + std::to_string(p.minConfidence));
  doTemporalFilter(state, u, w, prior, radial, points, confidence, mask, p);
}

}  // namespace cs

namespace cs {

void Backend::plainSupport(const Buffer& support, const Buffer& confidence, const Buffer& w, const Buffer& mask,
                           const Buffer& levelImage, const Buffer& levelMask) {
  const BackendContract c(*this, "plainSupport");
  c.buffer(mask, "mask", 1).sameGrid(confidence, "confidence", 1, mask, "mask").sameGrid(w, "w", 2, mask, "mask");
  c.buffer(support, "support", 6).sameGrid(levelImage, "levelImage", 1, support, "support");
  c.sameGrid(levelMask, "levelMask", 1, support, "support");
  c.require(support.width <= mask.width && support.height <= mask.height, "support is larger than the mask's grid");
  doPlainSupport(support, confidence, w, mask, levelImage, levelMask);
}

void Backend::fillPlanes(const Buffer& u, const Buffer& w, const Buffer& planeConfidence, const Buffer& labels,
                         const Buffer& planes, const Buffer& mask, const CameraParams& cam0, const double tPrime[3]) {
  const BackendContract c(*this, "fillPlanes");
  c.buffer(mask, "mask", 1).sameGrid(u, "u", 1, mask, "mask").sameGrid(w, "w", 2, mask, "mask");
  c.sameGrid(planeConfidence, "planeConfidence", 1, mask, "mask");
  c.buffer(labels, "labels", 2).buffer(planes, "planes", 1).camera(cam0, "cam0", &mask, "mask");
  c.require(labels.width <= mask.width && labels.height <= mask.height, "labels is larger than the mask's grid");
  c.require(planes.count() >= 3, "planes holds no plane");
  c.require(std::isfinite(tPrime[0]) && std::isfinite(tPrime[1]) && std::isfinite(tPrime[2]), "tPrime is not finite");
  doFillPlanes(u, w, planeConfidence, labels, planes, mask, cam0, tPrime);
}

void Backend::panoramaPlace(const Buffer& place, const Buffer& radial, const Buffer& rays, const PanoramaParams& p) {
  const BackendContract c(*this, "panoramaPlace");
  c.buffer(radial, "radial", 1).sameGrid(place, "place", kPanoramaPlaceChannels, radial, "radial");
  c.sameGrid(rays, "rays", 3, radial, "radial");
  c.require(p.width >= 4 && p.width <= 32768 && p.width % 2 == 0, "the panorama width must be even, 4..32768");
  c.require(std::isfinite(p.centre[0]) && std::isfinite(p.centre[1]) && std::isfinite(p.centre[2]),
            "the camera's centre is not finite");
  doPanoramaPlace(place, radial, rays, p);
}

void Backend::panoramaSplat(const Buffer& accum, const Buffer& place, const Buffer& confidence, const Buffer& grey,
                            const PanoramaParams& p) {
  const BackendContract c(*this, "panoramaSplat");
  c.buffer(place, "place", kPanoramaPlaceChannels).sameGrid(confidence, "confidence", 1, place, "place");
  if (grey.id >= 0) c.sameGrid(grey, "grey", 1, place, "place");
  c.buffer(accum, "accum", kPanoramaChannels);
  c.require(p.width >= 4 && p.width <= 32768 && p.width % 2 == 0, "the panorama width must be even, 4..32768");
  c.require(accum.width == p.width && accum.height == p.width / 2, "accum is not the panorama's size");
  c.require(p.pass >= kPanoramaBest && p.pass <= kPanoramaSums, "pass must be best, nearest or sums");
  c.require(!std::isnan(p.minConfidence), "minConfidence is NaN");
  doPanoramaSplat(accum, place, confidence, grey, p);
}

void Backend::panoramaResolve(const Buffer& range, const Buffer& grey, const Buffer& confidence, const Buffer& accum) {
  const BackendContract c(*this, "panoramaResolve");
  c.buffer(accum, "accum", kPanoramaChannels).sameGrid(range, "range", 1, accum, "accum");
  c.sameGrid(grey, "grey", 1, accum, "accum").sameGrid(confidence, "confidence", 1, accum, "accum");
  doPanoramaResolve(range, grey, confidence, accum);
}

void Backend::roundTrip(const Buffer& error, const Buffer& w, const Buffer& calibration, const Buffer& reverseW,
                        const Buffer& reverseCalibration, const Buffer& reverseMask, const Buffer& mask) {
  const BackendContract c(*this, "roundTrip");
  c.buffer(mask, "mask", 1).sameGrid(error, "error", 1, mask, "mask").sameGrid(w, "w", 2, mask, "mask");
  c.sameGrid(calibration, "calibration", 2, mask, "mask");
  c.buffer(reverseMask, "reverseMask", 1).sameGrid(reverseW, "reverseW", 2, reverseMask, "reverseMask");
  c.sameGrid(reverseCalibration, "reverseCalibration", 2, reverseMask, "reverseMask");
  doRoundTrip(error, w, calibration, reverseW, reverseCalibration, reverseMask, mask);
}

void Backend::resultConfidence(const Buffer& confidence, const Buffer& radial, const Buffer& points,
                               const Buffer& image, const Buffer& n0, const Buffer& n1, const Buffer& w,
                               const Buffer& trajectory, const Buffer& sweepConfidence, const Buffer& roundTripError,
                               const Buffer& planeConfidence, const Buffer& mask, const ConfidenceParams& p) {
  const BackendContract c(*this, "resultConfidence");
  c.buffer(mask, "mask", 1).sameGrid(confidence, "confidence", 1, mask, "mask");
  c.sameGrid(radial, "radial", 1, mask, "mask").sameGrid(points, "points", 3, mask, "mask");
  c.sameGrid(image, "image", 1, mask, "mask").sameGrid(n0, "n0", 1, mask, "mask").sameGrid(n1, "n1", 1, mask, "mask");
  c.sameGrid(w, "w", 2, mask, "mask").sameGrid(trajectory, "trajectory", 2, mask, "mask");
  if (sweepConfidence.id >= 0) c.sameGrid(sweepConfidence, "sweepConfidence", 1, mask, "mask");
  if (roundTripError.id >= 0) c.sameGrid(roundTripError, "roundTripError", 1, mask, "mask");
  if (planeConfidence.id >= 0) c.sameGrid(planeConfidence, "planeConfidence", 1, mask, "mask");
  c.require(confidence.id != radial.id, "confidence and radial are the same buffer");
  c.require(p.radius >= 0 && p.radius <= kMaxConfidenceRadius,
            "radius must be in [0, " + std::to_string(kMaxConfidenceRadius) + "], got " + std::to_string(p.radius));
  c.require(p.noise > 0.f && p.sigmaPx > 0.f && p.residualScale > 0.f && p.roundTripPx > 0.f,
            "noise, sigmaPx, residualScale and roundTripPx must be > 0");
  c.require(p.infinityPx >= 0.f && p.maxDeviationPx >= 0.f && p.infinityBoundPx >= 0.f,
            "infinityPx, maxDeviationPx and infinityBoundPx must be >= 0");
  c.require(p.invalidBelow >= 0.f && p.invalidBelow <= 1.f,
            "invalidBelow must be in [0, 1], got " + std::to_string(p.invalidBelow));
  doResultConfidence(confidence, radial, points, image, n0, n1, w, trajectory, sweepConfidence, roundTripError,
                     planeConfidence, mask, p);
}

void Backend::finishResult(const Buffer& valid, const Buffer& z, const Buffer& radial, const Buffer& points,
                           const Buffer& disparity, const Buffer& warp, const Buffer& confidence) {
  const BackendContract c(*this, "finishResult");
  c.buffer(radial, "radial", 1).sameGrid(valid, "valid", 1, radial, "radial").sameGrid(z, "z", 1, radial, "radial");
  c.sameGrid(points, "points", 3, radial, "radial").sameGrid(disparity, "disparity", 1, radial, "radial");
  c.sameGrid(warp, "warp", 2, radial, "radial").sameGrid(confidence, "confidence", 1, radial, "radial");
  const int ids[] = {valid.id, z.id, radial.id, points.id, disparity.id, warp.id, confidence.id};
  for (int i = 0; i < 7; ++i)
    for (int j = i + 1; j < 7; ++j) c.require(ids[i] != ids[j], "two of its buffers are the same buffer");
  doFinishResult(valid, z, radial, points, disparity, warp, confidence);
}

}  // namespace cs

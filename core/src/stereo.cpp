#include "curvestereo/stereo.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <new>

#include "curvestereo/backend.hpp"
#include "pipeline.hpp"
#include "stereo_core.hpp"

namespace cs {

namespace {

using detail::sizeText;

void checkImage(const ImageF& img, const Camera& cam, const char* which) {
  if (img.width != cam.width || img.height != cam.height)
    throw Error(std::string(which) + " image is " + sizeText(img.width, img.height) + " but the calibration says " +
                sizeText(cam.width, cam.height));
  // Branch-free within a block, so the compiler vectorises it: v - v is 0 for a finite v
  // and NaN for NaN or +-inf, which compares unequal to 0. (A float sum of v - v would not
  // vectorise: without -ffast-math the additions must stay in order.)
  constexpr size_t kBlock = 4096;
  const float* data = img.data.data();
  const size_t n = img.data.size();
  for (size_t start = 0; start < n; start += kBlock) {
    const size_t end = std::min(n, start + kBlock);
    int bad = 0;
    for (size_t i = start; i < end; ++i) bad |= !(data[i] - data[i] == 0.f);
    if (bad) throw Error(std::string(which) + " image contains NaN or infinite pixels");
  }
}

// v where keep is all ones, the quiet NaN where it is zero: a select written as bit
// operations, which the compiler vectorises where it would not if-convert `c ? v : nan`.
inline float keepOrNaN(float v, uint32_t keep) {
  constexpr uint32_t kQuietNaN = 0x7fc00000u;  // std::numeric_limits<float>::quiet_NaN()
  uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  bits = (bits & keep) | (kQuietNaN & ~keep);
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

// finish() for the common real-time selection, depth only (the valid mask comes from it):
// branch-free, so it vectorises.
void finishDepthOnly(DepthResult& r) {
  const size_t n = r.depth.radial.size();
  uint8_t* __restrict valid = r.valid.data.data();
  float* __restrict radial = r.depth.radial.data.data();
  float* __restrict confidence = r.confidence.empty() ? nullptr : r.confidence.data.data();
  for (size_t i = 0; i < n; ++i) {
    const float rad = radial[i];
    const bool solved = !std::isnan(rad);
    const uint32_t keep = 0u - uint32_t(solved);
    valid[i] = solved;
    radial[i] = keepOrNaN(rad, keep);
    if (confidence) confidence[i] = keepOrNaN(confidence[i], keep);
  }
}

// finish() with any of disparity, warp and points selected.
void finishAll(DepthResult& r) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const bool hasDisparity = !r.disparity.empty(), hasWarp = !r.warp.empty(), hasPoints = !r.depth.points.empty();
  const bool hasConfidence = !r.confidence.empty();
  for (size_t i = 0; i < r.depth.radial.size(); ++i) {
    float& radial = r.depth.radial.data[i];
    const bool solved = !std::isnan(radial) && (!hasDisparity || std::isfinite(r.disparity.data[i])) &&
                        (!hasWarp || (std::isfinite(r.warp.data[i].x) && std::isfinite(r.warp.data[i].y)));
    r.valid.data[i] = solved;
    if (!solved) {
      radial = nan;
      if (hasDisparity) r.disparity.data[i] = nan;
      if (hasWarp) r.warp.data[i] = {nan, nan};
      if (hasPoints) r.depth.points.data[i] = {nan, nan, nan};
      if (hasConfidence) r.confidence.data[i] = nan;
    }
    // A point at infinity has infinite z too (reported as +inf, also beyond 90 degrees).
    if (hasPoints) r.depth.z.data[i] = std::isinf(radial) ? radial : r.depth.points.data[i].z;
  }
}

// The pipeline's output as the public result, in one pass. A pixel is solved where the
// radial depth is not NaN (which includes the mask: Backend::triangulate leaves radial NaN
// wherever it is 0) and the disparity and warp, where selected, are finite: a solver
// failure, or a warp that left the camera model's valid region, is reported unsolved
// rather than passed on as if it were depth. Unsolved pixels are NaN in every output.
// Outputs not selected stay empty.
void finish(DepthResult& r) {
  const int w = r.depth.radial.width, h = r.depth.radial.height;
  fitImage(r.valid, w, h);
  if (r.depth.points.empty())
    r.depth.z = ImageF();
  else
    fitImage(r.depth.z, w, h);
  if (r.disparity.empty() && r.warp.empty() && r.depth.points.empty())
    finishDepthOnly(r);
  else
    finishAll(r);
}

// One frame of compute() or next(): the inputs checked against the rig, `solve` run, the
// time taken, and a host allocation failure reported as the frame's.
template <class Solve>
void timedSolve(const Rig& rig, const ImageF& left, const ImageF& right, DepthResult& result, Solve&& solve) {
  checkImage(left, rig.cam0, "left");
  checkImage(right, rig.cam1, "right");
  const auto t0 = std::chrono::steady_clock::now();
  try {
    solve();
  } catch (const std::bad_alloc&) {
    throw Error("out of memory computing a " + sizeText(left.width, left.height) + " frame (host result images)");
  }
  result.totalMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

Stereo::Stereo(const Rig& rig, const Params& params, const std::string& backend)
    : core_(std::make_unique<detail::StereoCore>(rig, params, [&] { return createBackend(backend, &backendWhy_); })) {}

Stereo::~Stereo() = default;

void Stereo::setPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) { core_->setPose(R, t); }

void Stereo::setMask(const ImageU8& mask) { core_->setMask(mask); }

void Stereo::setOutputs(const Outputs& outputs) {
  outputs_ = outputs;
  core_->pipeline().select({outputs.disparity, outputs.warp, outputs.points, outputs.confidence});
}

void Stereo::setProgress(std::function<void(double)> progress) { progress_ = std::move(progress); }

const std::string& Stereo::backendName() const { return core_->backendName(); }
std::string Stereo::deviceName() const { return core_->backend().device(); }
unsigned long long Stereo::bufferBytes() const { return Pipeline::bufferBytes(rig(), params()); }
const Rig& Stereo::rig() const { return core_->rig(); }
const Params& Stereo::params() const { return core_->params(); }

void Stereo::compute(const ImageF& left, const ImageF& right, DepthResult& result) {
  timedSolve(core_->rig(), left, right, result, [&] {
    core_->pipeline().run(left, right, profiling_, progress_, result);
    finish(result);
    result.lrPassShare = core_->pipeline().roundTripShare();
    result.warm = result.redone = false;
    result.consistentShare = std::numeric_limits<double>::quiet_NaN();
  });
}

void Stereo::next(const ImageF& left, const ImageF& right, DepthResult& result, const Pose* pose) {
  timedSolve(core_->rig(), left, right, result, [&] {
    Pipeline& pipeline = core_->pipeline();
    detail::StereoCore::SequenceFrame frame = core_->beginSequenceFrame(pose);
    auto solve = [&] {
      pipeline.run(left, right, profiling_, progress_, result, {frame.warm, frame.filter});
      finish(result);
      result.lrPassShare = pipeline.roundTripShare();
      // warmFailRatio 0 turns the check off, and with it the read of the sweep's confidence.
      result.consistentShare = core_->params().warmFailRatio > 0.f
                                   ? pipeline.consistentShare(core_->params().initAccept)
                                   : std::numeric_limits<double>::quiet_NaN();
    };
    solve();
    result.redone = false;
    if (frame.warm && core_->warmFailed(result.consistentShare)) {
      frame.warm = false;
      solve();
      result.redone = true;
    }
    result.warm = frame.warm;
    core_->endSequenceFrame(frame, result.consistentShare);
  });
}

DepthResult Stereo::next(const ImageF& left, const ImageF& right, const Pose* pose) {
  DepthResult result;
  next(left, right, result, pose);
  return result;
}

void Stereo::resetSequence() { core_->resetSequence(); }

DepthResult Stereo::compute(const ImageF& left, const ImageF& right) {
  DepthResult result;
  compute(left, right, result);
  return result;
}

}  // namespace cs

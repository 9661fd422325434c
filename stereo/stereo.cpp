#include "curvestereo/stereo.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <new>

#include "curvestereo/backend.hpp"
#include "pipeline.hpp"
#include "stereo_core.hpp"

namespace cs {

namespace {

using detail::sizeText;

// The sizes here; NaN and infinities as the pipeline copies the images (Pipeline::upload).
template <class Img>
void checkImage(const Img& img, const Camera& cam, const char* which) {
  if (img.width != cam.width || img.height != cam.height)
    throw Error(std::string(which) + " image is " + sizeText(img.width, img.height) + " but the calibration says " +
                sizeText(cam.width, cam.height));
}

// One frame of compute() or next(): the inputs checked against the rig, `solve` run, the
// time taken, and a host allocation failure reported as the frame's.
template <class Img, class Solve>
void timedSolve(const Rig& rig, const Img& left, const Img& right, DepthResult& result, Solve&& solve) {
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
    : core_(std::make_unique<detail::StereoCore>(rig, params, [&] { return createBackend(backend, &backendWhy_); })) {
  core_->pipeline().checkWarmFrames(params.warmFailRatio > 0.f);
}

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

template <class Img>
void Stereo::computeImages(const Img& left, const Img& right, DepthResult& result) {
  timedSolve(core_->rig(), left, right, result, [&] {
    core_->pipeline().run(left, right, profiling_, progress_, result);
    result.lrPassShare = core_->pipeline().roundTripShare();
    result.warm = result.redone = false;
    result.consistentShare = result.meanConfidence = std::numeric_limits<double>::quiet_NaN();
  });
}

template <class Img>
void Stereo::nextImages(const Img& left, const Img& right, DepthResult& result, const Pose* pose) {
  timedSolve(core_->rig(), left, right, result, [&] {
    Pipeline& pipeline = core_->pipeline();
    detail::StereoCore::SequenceFrame frame = core_->beginSequenceFrame(pose);
    auto solve = [&] {
      // warmFailRatio 0 turns the check off, and with it the read of the sweep's confidence.
      const bool checked = core_->params().warmFailRatio > 0.f;
      pipeline.run(left, right, profiling_, progress_, result, {frame.warm, frame.filter}, checked);
      result.lrPassShare = pipeline.roundTripShare();
      result.consistentShare = pipeline.consistentShare();
      result.meanConfidence = pipeline.meanConfidence();
    };
    solve();
    result.redone = false;
    if (frame.warm && core_->warmFailed(result.consistentShare, result.meanConfidence)) {
      frame.warm = false;
      solve();
      result.redone = true;
    }
    result.warm = frame.warm;
    core_->endSequenceFrame(frame, result.consistentShare, result.meanConfidence);
  });
}

void Stereo::compute(const ImageF& left, const ImageF& right, DepthResult& result) {
  computeImages(left, right, result);
}
void Stereo::compute(const ImageU8& left, const ImageU8& right, DepthResult& result) {
  computeImages(left, right, result);
}
void Stereo::next(const ImageF& left, const ImageF& right, DepthResult& result, const Pose* pose) {
  nextImages(left, right, result, pose);
}
void Stereo::next(const ImageU8& left, const ImageU8& right, DepthResult& result, const Pose* pose) {
  nextImages(left, right, result, pose);
}

DepthResult Stereo::compute(const ImageF& left, const ImageF& right) {
  DepthResult result;
  computeImages(left, right, result);
  return result;
}
DepthResult Stereo::compute(const ImageU8& left, const ImageU8& right) {
  DepthResult result;
  computeImages(left, right, result);
  return result;
}
DepthResult Stereo::next(const ImageF& left, const ImageF& right, const Pose* pose) {
  DepthResult result;
  nextImages(left, right, result, pose);
  return result;
}
DepthResult Stereo::next(const ImageU8& left, const ImageU8& right, const Pose* pose) {
  DepthResult result;
  nextImages(left, right, result, pose);
  return result;
}

void Stereo::resetSequence() { core_->resetSequence(); }

}  // namespace cs

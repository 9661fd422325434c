#include "stereo_core.hpp"

#include <new>

#include "curvestereo/backend.hpp"
#include "pipeline.hpp"

namespace cs::detail {

std::string sizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

void StereoCore::validate(const Rig& rig, const Params& params) {
  rig.validate();
  params.validate();
  // The cameras may differ in resolution: image 1 is resampled onto image 0's grid once
  // (the calibration warp), and everything after works there.
  for (const Camera* cam : {&rig.cam0, &rig.cam1}) {
    if (cam->width < kMinSide || cam->height < kMinSide)
      throw Error("images of " + sizeText(cam->width, cam->height) + " are too small (at least " +
                  sizeText(kMinSide, kMinSide) + ")");
    if (cam->width > kMaxSide || cam->height > kMaxSide)
      throw Error("images of " + sizeText(cam->width, cam->height) + " are too large (at most " +
                  std::to_string(kMaxSide) + " px per side)");
  }
}

// Every buffer of every level is allocated here, so this is where a frame too large for
// the device fails: say which frame, not just which buffer.
StereoCore::StereoCore(const Rig& rig, const Params& params,
                       const std::function<std::unique_ptr<Backend>()>& makeBackend)
    : rig_(rig), params_(params) {
  validate(rig_, params_);
  backend_ = makeBackend();
  backendName_ = backend_->name();
  const std::string frame = sizeText(rig_.cam0.width, rig_.cam0.height);
  const unsigned long long have = backend_->memoryBytes();
  auto refuse = [&](const char* needs, unsigned long long need) {
    throw Error("out of memory: a " + frame + " frame needs " + needs + std::to_string(need) +
                " bytes of buffers on backend " + backendName_ + ", which has " + std::to_string(have) + " bytes");
  };
  const unsigned long long atLeast = Pipeline::bufferBytesBeforeSweep(rig_, params_);
  if (have && atLeast > have) refuse("at least ", atLeast);
  const unsigned long long need = Pipeline::bufferBytes(rig_, params_);
  if (have && need > have) refuse("", need);
  try {
    pipeline_ = std::make_unique<Pipeline>(*backend_, rig_, params_, mask_);
    pipeline_->setPose(rig_.R, rig_.t);
  } catch (const std::bad_alloc&) {
    throw Error("out of memory setting up a " + frame + " frame on backend " + backendName_);
  } catch (const Error& e) {
    throw Error("cannot set up a " + frame + " frame on backend " + backendName_ + ": " + e.what());
  }
}

StereoCore::~StereoCore() = default;

void StereoCore::setPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Rig moved = rig_;
  moved.R = R;
  moved.t = t;
  moved.validate();
  rig_ = moved;
  pipeline_->setPose(R, t);
}

void StereoCore::setMask(const ImageU8& mask) {
  if (mask.width != rig_.cam0.width || mask.height != rig_.cam0.height)
    throw Error("mask is " + sizeText(mask.width, mask.height) + " but the images are " +
                sizeText(rig_.cam0.width, rig_.cam0.height));
  backend_->synchronize();  // a frame still queued (DeviceStereo) reads the old mask
  mask_ = mask;
  pipeline_->setUserMask(mask_);
  pipeline_->setPose(rig_.R, rig_.t);
}

DeviceIO StereoCore::deviceIO() const { return pipeline_->deviceIO(); }

void StereoCore::runOnDevice() { pipeline_->runOnDevice(); }

StereoCore::SequenceFrame StereoCore::beginSequenceFrame(const Pose* pose) {
  if (sequenceFrames_ == 0) pipeline_->resetSequence();
  const bool moved = pose && hasPose_ && sequenceFrames_ > 0;
  const Motion m = moved ? motionBetween(pose_, *pose) : Motion{};
  pipeline_->setMotion(m.R, m.t);
  hasPose_ = pose != nullptr;
  if (pose) pose_ = *pose;
  SequenceFrame frame;
  // The filter also records the state a warm frame carries (at strength 0, only that).
  frame.filter = params_.temporalStrength > 0 || (params_.warmStart && pipeline_->canWarmStart());
  const bool scheduledCold = params_.coldEvery > 0 && sequenceFrames_ % params_.coldEvery == 0;
  frame.warm = sequenceFrames_ > 0 && !scheduledCold && params_.warmStart && pipeline_->canWarmStart();
  return frame;
}

bool StereoCore::warmFailed(double share, double meanConfidence) const {
  const double r = params_.warmFailRatio;
  return share < r * coldShare_ || meanConfidence < r * coldConfidence_;
}

void StereoCore::endSequenceFrame(const SequenceFrame& frame, double share, double meanConfidence) {
  if (!frame.warm) coldShare_ = share, coldConfidence_ = meanConfidence;
  pipeline_->commitSequenceFrame();
  ++sequenceFrames_;
}

}  // namespace cs::detail

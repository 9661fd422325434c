// What cs::Stereo (stereo/stereo.cpp) and cs::cuda::DeviceStereo
// (stereo/device_stereo.cpp) share, written once: the validation of the rig, the
// parameters and a mask, the memory check, the pipeline's construction, and setPose /
// setMask. Internal (not installed).
#pragma once
#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>

#include "curvestereo/backend.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/pose.hpp"
#include "curvestereo/rig.hpp"

namespace cs {
class Pipeline;
}  // namespace cs

namespace cs::detail {

// The largest image side accepted (also the image readers' limit: larger is a corrupt
// calibration, not a camera) and the smallest.
constexpr int kMaxSide = 32768;
constexpr int kMinSide = 16;

std::string sizeText(int w, int h);

// The pipeline's buffers for callers whose images are on the backend's device
// (Pipeline::deviceIO).
struct DeviceIO {
  Buffer left, right;  // 1 ch, full resolution
  // Finished (Backend::finishResult): 1, 1, 2, 1, 3, 1, 1 ch.
  Buffer valid, disparity, warp, radial, points, z, confidence;
};

class StereoCore {
 public:
  // Validates the rig (Rig::validate, sizes kMinSide..kMaxSide per side; the cameras may
  // differ in resolution) and the parameters, then calls makeBackend (only when both are good),
  // checks that the frame's buffers fit in the backend's memory (Pipeline::bufferBytes
  // against Backend::memoryBytes) and builds the pipeline with the rig's pose. Every
  // failure is one cs::Error; the memory and set-up ones name the frame size and backend.
  StereoCore(const Rig& rig, const Params& params, const std::function<std::unique_ptr<Backend>()>& makeBackend);
  ~StereoCore();
  StereoCore(const StereoCore&) = delete;
  StereoCore& operator=(const StereoCore&) = delete;

  // The rig and parameter checks of the constructor, alone.
  static void validate(const Rig& rig, const Params& params);

  // A new relative pose (X1 = R X0 + t): validated as a rig, then the fields are redone.
  void setPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);
  // A mask of the images' size (else cs::Error naming both sizes). Work already queued
  // on the backend finishes first; the buffers stay (a recorded frame stays valid), and
  // the levels' masks and the fields are redone.
  void setMask(const ImageU8& mask);

  // DeviceStereo: fill io.left / io.right on the device, then runOnDevice() issues (or
  // replays) the frame with no host transfer and no synchronisation but, with plainFill,
  // the one wait for the host's plane fits.
  DeviceIO deviceIO() const;
  void runOnDevice();

  // --- sequences (Stereo::next, DeviceStereo::next): the schedule, written once ---
  // Decides the next frame's kind and prepares it: the first frame after a reset is cold
  // (and clears the carried state), then every Params::coldEvery-th; the others are warm
  // where the parameters allow (Pipeline::canWarmStart). pose (optional): camera 0's
  // T_world_cam0; the carried estimate moves by its change since the previous frame's pose
  // (none when either is missing: taken as it is).
  struct SequenceFrame {
    bool warm = false, filter = false;
  };
  SequenceFrame beginSequenceFrame(const Pose* pose);
  // Whether a warm frame failed: its share of left-right consistent pixels (`share`) or the
  // mean of its result's confidence (`meanConfidence`, Pipeline::meanConfidence) below
  // Params::warmFailRatio times the last cold frame's. NaN (not measured) never fails.
  bool warmFailed(double share, double meanConfidence) const;
  // The frame is done (cold with its figures, or warm): its state is carried into the next.
  void endSequenceFrame(const SequenceFrame& frame, double share, double meanConfidence);
  void resetSequence() { sequenceFrames_ = 0; }

  Backend& backend() { return *backend_; }
  const Backend& backend() const { return *backend_; }
  Pipeline& pipeline() { return *pipeline_; }
  const std::string& backendName() const { return backendName_; }
  const Rig& rig() const { return rig_; }
  const Params& params() const { return params_; }

 private:
  Rig rig_;
  Params params_;
  ImageU8 mask_;
  std::string backendName_;
  std::unique_ptr<Backend> backend_;
  std::unique_ptr<Pipeline> pipeline_;  // set by the constructor, which throws when it cannot
  long long sequenceFrames_ = 0;        // frames since the sequence's start (0: the next is the first)
  bool hasPose_ = false;                // the previous frame's pose, when it had one
  Pose pose_;
  double coldShare_ = 0;       // consistent share of the last cold frame
  double coldConfidence_ = 0;  // its mean confidence
};

}  // namespace cs::detail

// The public entry point: construct with a rig and parameters, then compute(left, right).
//
//   cs::Stereo stereo(cs::loadKalibr("camchain.yaml"));  // preset("realtime"), backend "auto"
//   cs::DepthResult r = stereo.compute(left, right);   // r.depth: radial metres
//   stereo.compute(left, right, r);                     // another pair, into r's buffers
//   stereo.next(left, right, r, &pose);                 // a sequence's next frame (warm start)
//
// A Stereo object is not thread-safe; use one per thread (they share nothing).
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "curvestereo/backends.hpp"
#include "curvestereo/depth_result.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/pose.hpp"
#include "curvestereo/rig.hpp"
#include "curvestereo/timing.hpp"
#include "curvestereo/triangulate.hpp"

namespace cs {

namespace detail {
class StereoCore;  // construction and validation shared with cs::cuda::DeviceStereo
}

class Stereo {
 public:
  // params: preset("realtime") unless given; backend: "auto", "cpu", ... (see
  // availableBackends()). Throws cs::Error on a bad rig, bad parameters, an unavailable
  // backend, images smaller than 16x16 or larger than 32768 px per side, or a frame whose
  // buffers do not fit in the backend's memory (the message names the frame size and the
  // bytes). The two cameras may differ in resolution: image 1 is resampled onto image 0's
  // grid (RigStereo solves a window of one camera against the whole other).
  explicit Stereo(const Rig& rig, const Params& params = preset("realtime"), const std::string& backend = "auto");
  ~Stereo();
  Stereo(const Stereo&) = delete;
  Stereo& operator=(const Stereo&) = delete;

  // For a moving camera: the pose of the second view relative to the first (X1 = R X0 + t)
  // changed. Recomputes the fields on the backend; throws cs::Error for a zero baseline
  // or a non-rotation.
  void setPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);
  // Restrict the solve to mask != 0 (e.g. a lens-shading mask); same size as the images
  // (else cs::Error). The buffers stay; the levels' masks and the fields are redone.
  void setMask(const ImageU8& mask);
  // Per-stage timing (DepthResult::stages). It costs a synchronisation at every stage
  // boundary and disables frame replay on GPU backends; off by default, on in bench.
  void setProfiling(bool on) { profiling_ = on; }
  // Which optional outputs compute() fills; `valid` and `depth.radial` always are. Fewer
  // outputs mean less to transfer from a GPU. Outputs left out are empty images
  // (depth.z comes with the points).
  struct Outputs {
    bool disparity = true, warp = true, points = true;
    bool confidence = true;
  };
  void setOutputs(const Outputs& outputs);
  // Called during compute(), on the calling thread, with the fraction of the solve done
  // (0..1), for progress bars: after every warp of every level as the frame is issued (a GPU
  // backend may still be running it), ending at 1. A frame that a GPU backend replays (CUDA
  // graph, Vulkan command buffer recorded by an earlier frame) reports only 0 when it is
  // submitted and 1 once its results are back: it is one submission with no host code
  // between its levels, and reporting per level would stall the real-time path there.
  void setProgress(std::function<void(double)> progress);
  // Images: float gray in [0,1], or a camera's 8-bit gray (v / 255, as the image files
  // are read: the same result as the float image, with a quarter of the bytes to copy and
  // transfer), both of the rig's resolution. Throws cs::Error on mismatched sizes or
  // non-finite pixels.
  DepthResult compute(const ImageF& left, const ImageF& right);
  DepthResult compute(const ImageU8& left, const ImageU8& right);
  // The same result, written into `result`: its images keep their storage where their size
  // already matches, so a loop that passes the same DepthResult every frame allocates
  // nothing after the first. Every field is overwritten (outputs not selected become empty
  // images). If it throws, `result` is left in an unspecified but valid state.
  void compute(const ImageF& left, const ImageF& right, DepthResult& result);
  void compute(const ImageU8& left, const ImageU8& right, DepthResult& result);

  // --- sequences: frame after frame of one rig (a live camera or a recording) ---
  // The next frame of a sequence. From the second frame on it starts from the previous
  // frame's estimate carried into this frame's view (Params::warmStart: with the band sweep
  // of realtime) and its result is filtered over time (Params::temporalStrength). `pose`
  // (optional) is camera 0's T_world_cam0 for this frame: with the previous frame's, the
  // carried estimate follows the rig's motion; without, it is carried as it is (the
  // temporal filter then resets wherever the image moved). Every Params::coldEvery-th frame
  // is solved cold, and a warm frame that fails (Params::warmFailRatio) is solved again cold
  // (result.redone). Same checks and outputs as compute(); result.warm says which it was.
  void next(const ImageF& left, const ImageF& right, DepthResult& result, const Pose* pose = nullptr);
  DepthResult next(const ImageF& left, const ImageF& right, const Pose* pose = nullptr);
  void next(const ImageU8& left, const ImageU8& right, DepthResult& result, const Pose* pose = nullptr);
  DepthResult next(const ImageU8& left, const ImageU8& right, const Pose* pose = nullptr);
  // A new sequence: the next frame is solved cold and nothing is carried into it.
  void resetSequence();

  const std::string& backendName() const;
  std::string deviceName() const;
  // Which backend "auto" took, and why (one line).
  const std::string& backendChoice() const { return backendWhy_; }
  const Rig& rig() const;
  const Params& params() const;
  // Bytes of the frame's buffers on the backend (every level's images, the sweep's volumes;
  // what the constructor checks against the device's memory). GPU backends hold the sweep
  // aggregation's three direction volumes besides (backend.hpp sweepAggregate).
  unsigned long long bufferBytes() const;

 private:
  // compute() and next() for either kind of image.
  template <class Img>
  void computeImages(const Img& left, const Img& right, DepthResult& result);
  template <class Img>
  void nextImages(const Img& left, const Img& right, DepthResult& result, const Pose* pose);
  std::string backendWhy_;
  std::unique_ptr<detail::StereoCore> core_;  // rig, parameters, backend, pipeline
  std::function<void(double)> progress_;
  bool profiling_ = false;
  Outputs outputs_;
};

}  // namespace cs

// CUDA entry point for callers whose images already live on the GPU: inputs are device
// pointers, outputs stay on the device, and all work is enqueued on the caller's
// cudaStream_t. The same pipeline as cs::Stereo on the CUDA backend (recorded once as CUDA
// graphs, then replayed). With plain_fill (on in every preset) a frame waits once on the
// host, between its solve and its finish, for the plane fits (docs/confidence.md); with
// plain_fill=false it never does.
//
//   cs::cuda::DeviceStereo stereo(rig, cs::preset("realtime"), stream);
//   cs::cuda::DeviceDepth d = stereo.compute(dLeft, dRight);  // enqueued on `stream`
//   myKernel<<<..., stream>>>(d.radial, ...);                  // ordered after it
//   d = stereo.next(dLeft, dRight, &pose);                     // a sequence's next frame (warm start)
//
// Only available when the library was built with CUDA (CS_HAVE_CUDA).
#pragma once
#include <cuda_runtime_api.h>

#include <Eigen/Core>
#include <memory>
#include <string>

#include "curvestereo/image.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/pose.hpp"
#include "curvestereo/rig.hpp"

namespace cs::cuda {

// Device pointers into buffers owned by the DeviceStereo, packed rows (width * channels
// floats), channels interleaved. They stay valid for the object's lifetime; their
// contents are those of the latest compute() or next() once the stream has reached it, and
// are overwritten by the next one.
// Every output is cs::Stereo's, pixel for pixel (the same finishing kernel): NaN wherever
// the pixel was not solved.
struct DeviceDepth {
  int width = 0, height = 0;
  const float* valid = nullptr;       // 1 ch: 1 where the pixel was solved, else 0
  const float* disparity = nullptr;   // 1 ch: u, px along the epipolar curve
  const float* warp = nullptr;        // 2 ch: w into the calibrated image 1
  const float* radial = nullptr;      // 1 ch: radial depth, m; +inf at infinity
  const float* points = nullptr;      // 3 ch: camera-0 points, m; NaN where infinite
  const float* z = nullptr;           // 1 ch: the points' z, m; +inf at infinity
  const float* confidence = nullptr;  // 1 ch: the result's confidence in [0, 1] (cs::DepthResult::confidence)
  // next(): whether the frame started from the previous frame's estimate (warm) or was
  // solved cold; false from compute().
  bool warm = false;
};

// "" when CUDA device `device` can run the backend, else the reason (e.g. "no CUDA
// device present").
std::string probe(int device = 0);

class DeviceStereo {
 public:
  // params: preset("realtime") unless given. stream: where every call enqueues its work; nullptr creates a private
  // non-blocking stream (see stream()). The legacy default stream (0 passed explicitly as cudaStreamLegacy) cannot be
  // recorded into a graph and is refused. device: the CUDA device index the stream belongs to. Validates as cs::Stereo
  // does (the same code): throws cs::Error on a bad rig or parameters, images smaller than 16x16 or larger than 32768
  // px per side, cameras of different resolutions (which cs::Stereo takes: compute() has one pitch for both), a frame
  // whose buffers do not fit in the device's memory, or when no usable CUDA device is present.
  explicit DeviceStereo(const Rig& rig, const Params& params = preset("realtime"), cudaStream_t stream = nullptr,
                        int device = 0);
  ~DeviceStereo();
  DeviceStereo(const DeviceStereo&) = delete;
  DeviceStereo& operator=(const DeviceStereo&) = delete;

  // A new relative pose (X1 = R X0 + t): the fields are recomputed on the device.
  void setPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);
  // Restrict the solve to mask != 0 (host image of the rig's size, else cs::Error), as
  // cs::Stereo::setMask: waits for the stream's queued work, keeps the buffers and the
  // recorded frame, and redoes the levels' masks and the fields.
  void setMask(const ImageU8& mask);

  // Enqueues one frame and returns at once. left / right: float gray in [0, 1] of the
  // rig's size on the device, rows pitchBytes apart (0: packed). They are read by the
  // time the stream reaches this frame's work; they are not checked for NaN.
  DeviceDepth compute(const float* left, const float* right, size_t pitchBytes = 0);

  // --- sequences: frame after frame of one rig, as cs::Stereo::next ---
  // Enqueues the next frame of a sequence and returns at once (inputs and outputs as
  // compute()). From the second frame on it starts from the previous frame's estimate
  // carried into this frame's view (Params::warmStart: with the band sweep of realtime) and
  // its result is filtered over time (Params::temporalStrength); the carried state stays
  // on the device. `pose` (optional): camera 0's T_world_cam0 for this frame; with the
  // previous frame's, the carried estimate follows the rig's motion, without it is carried
  // as it is. Each kind of frame (cold, warm) is recorded once and replayed with the
  // frame's own motion.
  // Unlike cs::Stereo::next, nothing is read back to the host, so there is no warm-failure
  // check: Params::warmFailRatio is ignored and a warm frame is never solved again cold.
  // Cold frames come only on the schedule: the first after construction or
  // resetSequence(), then every Params::coldEvery-th frame (0: none after the first), which
  // bounds how long a warm start can keep an error. DeviceDepth::warm says which it was.
  // compute() between next() calls solves a pair and leaves the carried state as it is.
  DeviceDepth next(const float* left, const float* right, const Pose* pose = nullptr, size_t pitchBytes = 0);
  // A new sequence: the next frame is solved cold and nothing is carried into it.
  void resetSequence();

  cudaStream_t stream() const;
  std::string deviceName() const;
  const Rig& rig() const;
  const Params& params() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cs::cuda

// cs::cuda::DeviceStereo: the core Pipeline on a CudaBackend that enqueues on the
// caller's stream, fed from and leaving its results in device memory.
#include <cuda_runtime.h>

#include <limits>

#include "cuda_backend.hpp"
#include "curvestereo/cuda.hpp"
#include "pipeline.hpp"
#include "stereo_core.hpp"

namespace cs::cuda {

std::string probe(int device) { return probeCuda(std::to_string(device)); }

struct DeviceStereo::Impl {
  CudaBackend* backend = nullptr;  // owned by core
  std::unique_ptr<detail::StereoCore> core;

  // The images from the caller's device memory into the pipeline's inputs.
  void takeInputs(const detail::DeviceIO& io, const float* left, const float* right, size_t pitchBytes) {
    backend->copyFromDevice(io.left, left, pitchBytes);
    backend->copyFromDevice(io.right, right, pitchBytes);
  }
  // The outputs' device memory (where every frame leaves them).
  DeviceDepth outputs(const detail::DeviceIO& io) {
    CudaBackend& b = *backend;
    DeviceDepth d;
    d.width = io.left.width;
    d.height = io.left.height;
    d.valid = b.devicePointer(io.valid);
    d.disparity = b.devicePointer(io.disparity);
    d.warp = b.devicePointer(io.warp);
    d.radial = b.devicePointer(io.radial);
    d.points = b.devicePointer(io.points);
    d.z = b.devicePointer(io.z);
    d.confidence = b.devicePointer(io.confidence);
    return d;
  }
};

// The construction and validation of cs::Stereo (detail::StereoCore), on a CudaBackend
// of the caller's stream.
DeviceStereo::DeviceStereo(const Rig& rig, const Params& params, cudaStream_t stream, int device)
    : impl_(std::make_unique<Impl>()) {
  if (rig.cam1.width != rig.cam0.width || rig.cam1.height != rig.cam0.height)  // compute() takes one pitch
    throw Error("cuda: DeviceStereo needs both cameras at one resolution, and these differ (" +
                detail::sizeText(rig.cam0.width, rig.cam0.height) + " and " +
                detail::sizeText(rig.cam1.width, rig.cam1.height) + ")");
  impl_->core = std::make_unique<detail::StereoCore>(rig, params, [&]() -> std::unique_ptr<Backend> {
    if (stream == cudaStreamLegacy)
      throw Error("cuda: the legacy default stream cannot be recorded into a graph; pass a created stream or nullptr");
    const std::string why = probeCuda(std::to_string(device));
    if (!why.empty()) throw Error("cuda: " + why);
    auto backend = std::make_unique<CudaBackend>(device, stream);
    impl_->backend = backend.get();
    return backend;
  });
}

DeviceStereo::~DeviceStereo() = default;

void DeviceStereo::setPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) { impl_->core->setPose(R, t); }

void DeviceStereo::setMask(const ImageU8& mask) { impl_->core->setMask(mask); }

DeviceDepth DeviceStereo::compute(const float* left, const float* right, size_t pitchBytes) {
  if (!left || !right) throw Error("cuda: DeviceStereo::compute needs two device images");
  const detail::DeviceIO io = impl_->core->deviceIO();
  impl_->takeInputs(io, left, right, pitchBytes);
  impl_->core->runOnDevice();
  return impl_->outputs(io);
}

// cs::Stereo::next's schedule (detail::StereoCore) without its readback: the frame's share
// of consistent pixels is never known here, so the core is told NaN (it then judges no warm
// frame failed, and DeviceStereo never asks).
DeviceDepth DeviceStereo::next(const float* left, const float* right, const Pose* pose, size_t pitchBytes) {
  if (!left || !right) throw Error("cuda: DeviceStereo::next needs two device images");
  detail::StereoCore& core = *impl_->core;
  const detail::StereoCore::SequenceFrame frame = core.beginSequenceFrame(pose);
  const detail::DeviceIO io = core.deviceIO();
  impl_->takeInputs(io, left, right, pitchBytes);
  core.pipeline().runOnDevice(FrameKind{frame.warm, frame.filter});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  core.endSequenceFrame(frame, nan, nan);
  impl_->backend->enqueueQueued();  // the commit of the carried state, on the stream now
  DeviceDepth d = impl_->outputs(io);
  d.warm = frame.warm;
  return d;
}

void DeviceStereo::resetSequence() { impl_->core->resetSequence(); }

cudaStream_t DeviceStereo::stream() const { return impl_->backend->stream(); }
std::string DeviceStereo::deviceName() const { return impl_->backend->device(); }
const Rig& DeviceStereo::rig() const { return impl_->core->rig(); }
const Params& DeviceStereo::params() const { return impl_->core->params(); }

}  // namespace cs::cuda

// cs::cuda::DeviceStereo: the core Pipeline on a CudaBackend that enqueues on the
// caller's stream, fed from and leaving its results in device memory.
#include <cuda_runtime.h>

#include "cuda_backend.hpp"
#include "curvestereo/cuda.hpp"
#include "stereo_core.hpp"

namespace cs::cuda {

std::string probe(int device) { return probeCuda(std::to_string(device)); }

struct DeviceStereo::Impl {
  CudaBackend* backend = nullptr;  // owned by core
  std::unique_ptr<detail::StereoCore> core;
};

// The construction and validation of cs::Stereo (detail::StereoCore), on a CudaBackend
// of the caller's stream.
DeviceStereo::DeviceStereo(const Rig& rig, const Params& params, cudaStream_t stream, int device)
    : impl_(std::make_unique<Impl>()) {
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
  CudaBackend& b = *impl_->backend;
  b.copyFromDevice(io.left, left, pitchBytes);
  b.copyFromDevice(io.right, right, pitchBytes);
  impl_->core->runOnDevice();
  DeviceDepth d;
  d.width = io.left.width;
  d.height = io.left.height;
  d.valid = b.devicePointer(io.valid);
  d.disparity = b.devicePointer(io.disparity);
  d.warp = b.devicePointer(io.warp);
  d.radial = b.devicePointer(io.radial);
  d.points = b.devicePointer(io.points);
  d.confidence = io.confidence.id >= 0 ? b.devicePointer(io.confidence) : nullptr;
  return d;
}

cudaStream_t DeviceStereo::stream() const { return impl_->backend->stream(); }
std::string DeviceStereo::deviceName() const { return impl_->backend->device(); }
const Rig& DeviceStereo::rig() const { return impl_->core->rig(); }
const Params& DeviceStereo::params() const { return impl_->core->params(); }

}  // namespace cs::cuda

// cs::cuda::DeviceStereo: the core Pipeline on a CudaBackend that enqueues on the
// caller's stream, fed from and leaving its results in device memory.
#include <cuda_runtime.h>

#include "cuda_backend.hpp"
#include "curvestereo/cuda.hpp"
#include "pipeline.hpp"

namespace cs::cuda {

std::string probe(int device) { return probeCuda(std::to_string(device)); }

struct DeviceStereo::Impl {
  Rig rig;
  Params params;
  ImageU8 mask;
  std::unique_ptr<CudaBackend> backend;
  std::unique_ptr<Pipeline> pipeline;

  void rebuild() {
    pipeline = std::make_unique<Pipeline>(*backend, rig, params, mask);
    pipeline->setPose(rig.R, rig.t);
  }
};

DeviceStereo::DeviceStereo(const Rig& rig, const Params& params, cudaStream_t stream, int device)
    : impl_(std::make_unique<Impl>()) {
  rig.validate();
  params.validate();
  if (rig.cam0.width < 16 || rig.cam0.height < 16) throw Error("images must be at least 16x16");
  if (rig.cam1.width != rig.cam0.width || rig.cam1.height != rig.cam0.height)
    throw Error("the cameras differ in resolution: both images must have the same size");
  if (stream == cudaStreamLegacy)
    throw Error("cuda: the legacy default stream cannot be recorded into a graph; pass a created stream or nullptr");
  const std::string why = probeCuda(std::to_string(device));
  if (!why.empty()) throw Error("cuda: " + why);
  impl_->rig = rig;
  impl_->params = params;
  impl_->backend = std::make_unique<CudaBackend>(device, stream);
  impl_->rebuild();
}

DeviceStereo::~DeviceStereo() = default;

void DeviceStereo::setPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Rig moved = impl_->rig;
  moved.R = R;
  moved.t = t;
  moved.validate();
  impl_->rig = moved;
  impl_->pipeline->setPose(R, t);
}

void DeviceStereo::setMask(const ImageU8& mask) {
  if (mask.width != impl_->rig.cam0.width || mask.height != impl_->rig.cam0.height)
    throw Error("mask size differs from the image size");
  impl_->backend->synchronize();
  impl_->mask = mask;
  impl_->rebuild();
}

DeviceDepth DeviceStereo::compute(const float* left, const float* right, size_t pitchBytes) {
  if (!left || !right) throw Error("cuda: DeviceStereo::compute needs two device images");
  const Pipeline::DeviceIO io = impl_->pipeline->deviceIO();
  CudaBackend& b = *impl_->backend;
  b.copyFromDevice(io.left, left, pitchBytes);
  b.copyFromDevice(io.right, right, pitchBytes);
  impl_->pipeline->runOnDevice();
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
const Rig& DeviceStereo::rig() const { return impl_->rig; }
const Params& DeviceStereo::params() const { return impl_->params; }

}  // namespace cs::cuda

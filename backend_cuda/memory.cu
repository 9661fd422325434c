// fill() and copy(): queued copies and fills of disjoint buffers run as one launch.
#include <algorithm>
#include <cstdint>

#include "common.cuh"

namespace cs::cudak {

namespace {
__global__ void fillKernel(float* data, size_t count, float value) {
  for (size_t i = blockIdx.x * size_t(blockDim.x) + threadIdx.x; i < count; i += size_t(gridDim.x) * blockDim.x)
    data[i] = value;
}
__global__ void memOpsKernel(MemOps ops) {
  const MemOp o = ops.op[blockIdx.y];
  const size_t stride = size_t(gridDim.x) * blockDim.x;
  const size_t first = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
  const bool vector = o.count % 4 == 0 && reinterpret_cast<uintptr_t>(o.dst) % 16 == 0 &&
                      (!o.src || reinterpret_cast<uintptr_t>(o.src) % 16 == 0);
  if (vector) {
    float4* dst = reinterpret_cast<float4*>(o.dst);
    const float4* src = reinterpret_cast<const float4*>(o.src);
    const float4 value = make_float4(o.value, o.value, o.value, o.value);
    for (size_t i = first; i < o.count / 4; i += stride) dst[i] = src ? src[i] : value;
  } else {
    for (size_t i = first; i < o.count; i += stride) o.dst[i] = o.src ? o.src[i] : o.value;
  }
}
}  // namespace

cudaError_t launchMemOps(cudaStream_t s, const MemOps& ops) {
  if (ops.count <= 0) return cudaSuccess;
  size_t largest = 0;
  for (int i = 0; i < ops.count; ++i) largest = std::max(largest, ops.op[i].count);
  const unsigned blocks = unsigned(std::max<size_t>(1, std::min<size_t>((largest / 4 + 255) / 256, 2048)));
  memOpsKernel<<<dim3(blocks, unsigned(ops.count)), 256, 0, s>>>(ops);
  return cudaGetLastError();
}

cudaError_t launchFill(cudaStream_t s, float* data, size_t count, float value) {
  const unsigned blocks = unsigned(std::min<size_t>((count + 255) / 256, 4096));
  fillKernel<<<blocks, 256, 0, s>>>(data, count, value);
  return cudaGetLastError();
}

}  // namespace cs::cudak

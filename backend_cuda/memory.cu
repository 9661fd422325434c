// fill() with a non-zero value (zero goes through cudaMemsetAsync).
#include <algorithm>

#include "common.cuh"

namespace cs::cudak {

namespace {
__global__ void fillKernel(float* data, size_t count, float value) {
  for (size_t i = blockIdx.x * size_t(blockDim.x) + threadIdx.x; i < count; i += size_t(gridDim.x) * blockDim.x)
    data[i] = value;
}
}  // namespace

cudaError_t launchFill(cudaStream_t s, float* data, size_t count, float value) {
  const unsigned blocks = unsigned(std::min<size_t>((count + 255) / 256, 4096));
  fillKernel<<<blocks, 256, 0, s>>>(data, count, value);
  return cudaGetLastError();
}

}  // namespace cs::cudak

// 3x3 median of u over the masked neighbours (cpu/median.cpp); even counts take the mean
// of the two middle values.
#include "common.cuh"

namespace cs::cudak {

namespace {
__global__ void medianKernel(Img dst, Img src, Img mask) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= dst.width || y >= dst.height) return;
  if (!masked(mask, x, y)) {
    at(dst, x, y) = at(src, x, y);
    return;
  }
  float values[9];
  int n = 0;
#pragma unroll
  for (int dy = -1; dy <= 1; ++dy)
#pragma unroll
    for (int dx = -1; dx <= 1; ++dx)
      if (masked(mask, x + dx, y + dy)) values[n++] = __ldg(&at(src, x + dx, y + dy));
  // Insertion sort of at most 9 values.
  for (int i = 1; i < n; ++i) {
    const float v = values[i];
    int j = i - 1;
    while (j >= 0 && values[j] > v) {
      values[j + 1] = values[j];
      --j;
    }
    values[j + 1] = v;
  }
  float upper = values[n / 2];
  if (n % 2 == 0) upper = 0.5f * (values[n / 2 - 1] + upper);
  at(dst, x, y) = upper;
}
}  // namespace

cudaError_t launchMedian(cudaStream_t s, Img dst, Img src, Img mask) {
  const dim3 block(32, 8);
  medianKernel<<<grid2d(dst.width, dst.height, block), block, 0, s>>>(dst, src, mask);
  return cudaGetLastError();
}

}  // namespace cs::cudak

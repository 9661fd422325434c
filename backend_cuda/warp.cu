// dst(x) = src(x + flow(x)), bilinear, clamped to the image edge (cpu/warp.cpp).
#include "common.cuh"

namespace cs::cudak {

namespace {
__global__ void warpKernel(Img dst, Img src, Img flow) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= dst.width || y >= dst.height) return;
  const float sx = float(x) + at(flow, x, y, 0), sy = float(y) + at(flow, x, y, 1);
  for (int c = 0; c < dst.channels; ++c) at(dst, x, y, c) = sampleBilinear(src, sx, sy, c);
}
}  // namespace

cudaError_t launchWarp(cudaStream_t s, Img dst, Img src, Img flow) {
  const dim3 block(32, 8);
  CS_LAUNCH(warpKernel, grid2d(dst.width, dst.height, block), block, 0, s, dst, src, flow);
  return cudaGetLastError();
}

}  // namespace cs::cudak

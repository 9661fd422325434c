// du = clamp(u - u0, +-duMax); u = u0 + du; w += du * tangent (cpu/accumulate.cpp).
#include "common.cuh"

namespace cs::cudak {

namespace {
__global__ void accumulateKernel(Img u, Img w, Img u0, Img tangent, Img mask, float duMax) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= u.width || y >= u.height || !masked(mask, x, y)) return;
  const float du = fminf(fmaxf(at(u, x, y) - at(u0, x, y), -duMax), duMax);
  at(u, x, y) = at(u0, x, y) + du;
  at(w, x, y, 0) += du * at(tangent, x, y, 0);
  at(w, x, y, 1) += du * at(tangent, x, y, 1);
}
}  // namespace

cudaError_t launchAccumulate(cudaStream_t s, Img u, Img w, Img u0, Img tangent, Img mask, float duMax) {
  const dim3 block(32, 8);
  accumulateKernel<<<grid2d(u.width, u.height, block), block, 0, s>>>(u, w, u0, tangent, mask, duMax);
  return cudaGetLastError();
}

}  // namespace cs::cudak

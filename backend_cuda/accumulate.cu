// du = clamp(u - u0, +-duMax); u = u0 + du; w += du * tangent (cpu/accumulate.cpp). u may be
// read from another buffer (the median's output) whose copy to u this launch replaces.
#include "common.cuh"

namespace cs::cudak {

namespace {
__global__ void accumulateKernel(Img u, const float* uIn, Img w, Img u0, Img tangent, Img mask, float duMax) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= u.width || y >= u.height) return;
  const size_t i = size_t(y) * u.width + x;
  if (!masked(mask, x, y)) {
    if (uIn != u.data) u.data[i] = uIn[i];
    return;
  }
  const float du = fminf(fmaxf(uIn[i] - at(u0, x, y), -duMax), duMax);
  at(u, x, y) = at(u0, x, y) + du;
  at(w, x, y, 0) += du * at(tangent, x, y, 0);
  at(w, x, y, 1) += du * at(tangent, x, y, 1);
}
}  // namespace

cudaError_t launchAccumulate(cudaStream_t s, Img u, const float* uIn, Img w, Img u0, Img tangent, Img mask,
                             float duMax) {
  const dim3 block(32, 8);
  CS_LAUNCH(accumulateKernel, grid2d(u.width, u.height, block), block, 0, s, u, uIn, w, u0, tangent, mask, duMax);
  return cudaGetLastError();
}

}  // namespace cs::cudak

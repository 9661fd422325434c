// Per warp: the tangent of the epipolar curve at x + w and the linearised data term
// there (cpu/warp_derivatives.cpp). After the first warp of a level the backend computes
// them in the previous warp's median + accumulate pass instead (median.cu).
#include "warp_derivatives.cuh"

namespace cs::cudak {

namespace {

__global__ void warpDerivativesKernel(Img u0, DataTermOut out, DataTermIn in, Img w, Img u) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= in.mask.width || y >= in.mask.height) return;
  at(u0, x, y) = at(u, x, y);
  const bool isMasked = at(in.mask, x, y) != 0.f;
  dataTermAt(out, in, x, y, isMasked, isMasked ? at(w, x, y, 0) : 0.f, isMasked ? at(w, x, y, 1) : 0.f);
}

}  // namespace

cudaError_t launchWarpDerivatives(cudaStream_t s, Img u0, const DataTermOut& out, const DataTermIn& in, Img w, Img u) {
  const dim3 block(32, 8);
  CS_LAUNCH(warpDerivativesKernel, grid2d(in.mask.width, in.mask.height, block), block, 0, s, u0, out, in, w, u);
  return cudaGetLastError();
}

}  // namespace cs::cudak

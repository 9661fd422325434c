// The result as the user sees it (cpu/finish_result.cpp, backend.hpp finishResult):
// unsolved pixels NaN in every output, the valid mask and z. One thread a pixel.
#include "common.cuh"

namespace cs::cudak {

namespace {

__global__ void finishResultKernel(float* valid, float* z, float* radial, float* points, float* disparity, float* warp,
                                   float* confidence, long long n) {
  const long long i = (long long)blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  const float r = radial[i];
  if (!isnan(r) && isfinite(disparity[i]) && isfinite(warp[2 * i]) && isfinite(warp[2 * i + 1])) {
    valid[i] = 1.f;
    z[i] = isinf(r) ? r : points[3 * i + 2];
    return;
  }
  const float nan = __int_as_float(0x7fc00000);  // the oracle's quiet NaN, bit for bit
  valid[i] = 0.f;
  z[i] = radial[i] = disparity[i] = confidence[i] = nan;
  warp[2 * i] = warp[2 * i + 1] = nan;
  points[3 * i] = points[3 * i + 1] = points[3 * i + 2] = nan;
}

}  // namespace

cudaError_t launchFinishResult(cudaStream_t s, Img valid, Img z, Img radial, Img points, Img disparity, Img warp,
                               Img confidence) {
  const long long n = (long long)radial.width * radial.height;
  const int block = 256;
  CS_LAUNCH(finishResultKernel, unsigned((n + block - 1) / block), block, 0, s, valid.data, z.data, radial.data,
            points.data, disparity.data, warp.data, confidence.data, n);
  return cudaGetLastError();
}

}  // namespace cs::cudak

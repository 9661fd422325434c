// The left-right round trip of the final result (cpu/round_trip.cpp, backend.hpp
// roundTrip): x into image 1 by this solve's w and the calibration field, back into image 0
// by the other direction's. One thread a pixel, the oracle's float arithmetic.
#include "common.cuh"

namespace cs::cudak {

namespace {

__device__ __forceinline__ bool insideImage(const Img& v, float x, float y) {
  return x >= 0.f && y >= 0.f && x <= float(v.width - 1) && y <= float(v.height - 1);
}

__device__ float roundTripAt(int x, int y, const Img& w, const Img& calibration, const Img& reverseW,
                             const Img& reverseCalibration, const Img& reverseMask) {
  const float nan = __int_as_float(0x7fc00000);
  const float ax = __fadd_rn(float(x), at(w, x, y, 0)), ay = __fadd_rn(float(y), at(w, x, y, 1));
  if (!insideImage(calibration, ax, ay)) return nan;
  const float yx = __fadd_rn(ax, sampleBilinear(calibration, ax, ay, 0));
  const float yy = __fadd_rn(ay, sampleBilinear(calibration, ax, ay, 1));
  if (!insideImage(reverseW, yx, yy)) return nan;
  if (at(reverseMask, int(floorf(yx + 0.5f)), int(floorf(yy + 0.5f))) == 0.f) return nan;
  const float bx = __fadd_rn(yx, sampleBilinear(reverseW, yx, yy, 0));
  const float by = __fadd_rn(yy, sampleBilinear(reverseW, yx, yy, 1));
  if (!insideImage(reverseCalibration, bx, by)) return nan;
  const float zx = __fadd_rn(bx, sampleBilinear(reverseCalibration, bx, by, 0));
  const float zy = __fadd_rn(by, sampleBilinear(reverseCalibration, bx, by, 1));
  const float dx = zx - float(x), dy = zy - float(y);
  const float e = sqrtf(__fadd_rn(__fmul_rn(dx, dx), __fmul_rn(dy, dy)));
  return isfinite(e) ? e : nan;
}

__global__ void roundTripKernel(Img error, Img w, Img calibration, Img reverseW, Img reverseCalibration,
                                Img reverseMask, Img mask) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= error.width || y >= error.height) return;
  at(error, x, y) = masked(mask, x, y) ? roundTripAt(x, y, w, calibration, reverseW, reverseCalibration, reverseMask)
                                       : __int_as_float(0x7fc00000);
}

}  // namespace

cudaError_t launchRoundTrip(cudaStream_t s, Img error, Img w, Img calibration, Img reverseW, Img reverseCalibration,
                            Img reverseMask, Img mask) {
  const dim3 block(32, 8);
  CS_LAUNCH(roundTripKernel, grid2d(error.width, error.height, block), block, 0, s, error, w, calibration, reverseW,
            reverseCalibration, reverseMask, mask);
  return cudaGetLastError();
}

}  // namespace cs::cudak

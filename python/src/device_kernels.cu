// See device_kernels.hpp. Built with --fmad=false: grayAt must round as the host does.
#include "device_kernels.hpp"

namespace cs::py {

namespace {

__global__ void toGrayKernel(StridedPixels src, int type, int width, int height, float* dst, unsigned* flag,
                             unsigned bit) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= width || y >= height) return;
  const float v = grayAt(src, type, y, x);
  dst[size_t(y) * width + x] = v;
  if (!(v - v == 0.f)) atomicOr(flag, bit);  // NaN or +-inf, the host API's test
}

// The host's NaN (std::numeric_limits<float>::quiet_NaN()), bit for bit.
__device__ inline float quietNaN() { return __int_as_float(0x7fc00000); }

__global__ void finishKernel(FinishArgs a) {
  const long long i = (long long)blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= a.n) return;
  const float nan = quietNaN();
  const bool any = a.withDisparity || a.withWarp || a.withPoints;
  float radial = a.radial[i];
  bool solved = !isnan(radial);
  if (any) {
    if (a.withDisparity) solved = solved && isfinite(a.disparity[i]);
    if (a.withWarp) solved = solved && isfinite(a.warp[2 * i]) && isfinite(a.warp[2 * i + 1]);
  }
  if (!solved) radial = nan;
  a.valid[i] = solved;
  a.outRadial[i] = radial;
  if (a.outConfidence) a.outConfidence[i] = solved ? a.confidence[i] : nan;
  if (a.outDisparity) a.outDisparity[i] = solved ? a.disparity[i] : nan;
  if (a.outWarp) {
    a.outWarp[2 * i] = solved ? a.warp[2 * i] : nan;
    a.outWarp[2 * i + 1] = solved ? a.warp[2 * i + 1] : nan;
  }
  if (a.outPoints) {
    float p[3];
    for (int c = 0; c < 3; ++c) p[c] = solved ? a.points[3 * i + c] : nan;
    for (int c = 0; c < 3; ++c) a.outPoints[3 * i + c] = p[c];
    // A point at infinity has infinite z too (finishAll).
    if (a.outZ) a.outZ[i] = isinf(radial) ? radial : p[2];
  }
}

}  // namespace

cudaError_t launchToGray(const StridedPixels& src, int type, int width, int height, float* dst, unsigned* flag,
                         unsigned bit, cudaStream_t stream) {
  const dim3 block(32, 8), grid((width + 31) / 32, (height + 7) / 8);
  toGrayKernel<<<grid, block, 0, stream>>>(src, type, width, height, dst, flag, bit);
  return cudaGetLastError();
}

cudaError_t launchFinish(const FinishArgs& args, cudaStream_t stream) {
  if (args.n == 0) return cudaSuccess;
  const int block = 256;
  finishKernel<<<unsigned((args.n + block - 1) / block), block, 0, stream>>>(args);
  return cudaGetLastError();
}

}  // namespace cs::py

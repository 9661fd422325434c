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

__global__ void packResultKernel(PackArgs a) {
  const long long i = (long long)blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= a.n) return;
  a.valid[i] = a.validIn[i] != 0.f;
  a.outRadial[i] = a.radial[i];
  if (a.outZ) a.outZ[i] = a.z[i];
  if (a.outConfidence) a.outConfidence[i] = a.confidence[i];
  if (a.outDisparity) a.outDisparity[i] = a.disparity[i];
  if (a.outWarp)
    for (int c = 0; c < 2; ++c) a.outWarp[2 * i + c] = a.warp[2 * i + c];
  if (a.outPoints)
    for (int c = 0; c < 3; ++c) a.outPoints[3 * i + c] = a.points[3 * i + c];
}

}  // namespace

cudaError_t launchToGray(const StridedPixels& src, int type, int width, int height, float* dst, unsigned* flag,
                         unsigned bit, cudaStream_t stream) {
  const dim3 block(32, 8), grid((width + 31) / 32, (height + 7) / 8);
  toGrayKernel<<<grid, block, 0, stream>>>(src, type, width, height, dst, flag, bit);
  return cudaGetLastError();
}

cudaError_t launchPackResult(const PackArgs& args, cudaStream_t stream) {
  if (args.n == 0) return cudaSuccess;
  const int block = 256;
  packResultKernel<<<unsigned((args.n + block - 1) / block), block, 0, stream>>>(args);
  return cudaGetLastError();
}

}  // namespace cs::py

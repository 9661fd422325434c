// Pyramid resampling (cpu/resample.cpp): fine x maps to coarse (x + 0.5) / scale - 0.5.
#include "common.cuh"

namespace cs::cudak {

namespace {

__global__ void downsampleKernel(Img dst, Img src, float scale, float sigma, int radius) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= dst.width || y >= dst.height) return;
  const float cy = (float(y) + 0.5f) * scale - 0.5f;
  const float cx = (float(x) + 0.5f) * scale - 0.5f;
  const int fy = int(floorf(cy)), fx = int(floorf(cx));
  for (int c = 0; c < dst.channels; ++c) {
    float sum = 0.f, weights = 0.f;
    for (int j = fy - radius + 1; j <= fy + radius; ++j)
      for (int i = fx - radius + 1; i <= fx + radius; ++i) {
        const float dx = float(i) - cx, dy = float(j) - cy;
        const float wgt = expf(-(dx * dx + dy * dy) / (2.f * sigma * sigma));
        const int sx = min(max(i, 0), src.width - 1), sy = min(max(j, 0), src.height - 1);
        sum += wgt * __ldg(&at(src, sx, sy, c));
        weights += wgt;
      }
    at(dst, x, y, c) = sum / weights;
  }
}

__global__ void upsampleKernel(Img dst, Img src, float scale, float valueScale) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= dst.width || y >= dst.height) return;
  const float sy = (float(y) + 0.5f) / scale - 0.5f;
  const float sx = (float(x) + 0.5f) / scale - 0.5f;
  for (int c = 0; c < dst.channels; ++c) at(dst, x, y, c) = valueScale * sampleBilinear(src, sx, sy, c);
}

}  // namespace

cudaError_t launchDownsample(cudaStream_t s, Img dst, Img src, float scale) {
  const float sigma = 0.5f * scale;  // decimationSigma
  const int radius = int(ceilf(2.f * sigma));
  const dim3 block(32, 8);
  CS_LAUNCH(downsampleKernel, grid2d(dst.width, dst.height, block), block, 0, s, dst, src, scale, sigma, radius);
  return cudaGetLastError();
}

cudaError_t launchUpsample(cudaStream_t s, Img dst, Img src, float scale, float valueScale) {
  const dim3 block(32, 8);
  CS_LAUNCH(upsampleKernel, grid2d(dst.width, dst.height, block), block, 0, s, dst, src, scale, valueScale);
  return cudaGetLastError();
}

}  // namespace cs::cudak

// Local contrast normalisation (cpu/normalise.cpp): a horizontal pass writes the masked,
// tap-weighted sums of 1, I and I^2 along each row into `moments`; a vertical pass sums
// those over the column and writes (I - mean) / sqrt(max(0, var) + eps^2). Each thread
// adds its terms in the oracle's order (taps from -r to r) and the kernels are built
// without contraction (--fmad=false), with IEEE division and square root, so results
// agree with the oracle to the bit on the same inputs.
#include "common.cuh"

namespace cs::cudak {

namespace {

__global__ void normaliseMomentsKernel(Img moments, Img src, Img mask, NormaliseParams p) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= src.width || y >= src.height) return;
  const int r = p.radius;
  const float* srcRow = src.data + size_t(y) * src.width;
  const float* maskRow = mask.data + size_t(y) * mask.width;
  float s0 = 0.f, s1 = 0.f, s2 = 0.f;
  for (int i = -r; i <= r; ++i) {
    const int sx = x + i;
    if (sx < 0 || sx >= src.width || __ldg(&maskRow[sx]) == 0.f) continue;
    const float t = p.taps[i + r], v = __ldg(&srcRow[sx]);
    s0 += t;
    s1 += t * v;
    s2 += t * (v * v);
  }
  float* m = moments.data + (size_t(y) * moments.width + x) * 3;
  m[0] = s0, m[1] = s1, m[2] = s2;
}

__global__ void normaliseKernel(Img dst, Img moments, Img src, Img mask, NormaliseParams p) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= dst.width || y >= dst.height) return;
  if (!masked(mask, x, y)) {
    at(dst, x, y) = 0.f;
    return;
  }
  const int r = p.radius;
  float s0 = 0.f, s1 = 0.f, s2 = 0.f;
  for (int j = -r; j <= r; ++j) {
    const int sy = y + j;
    if (sy < 0 || sy >= src.height) continue;
    const float t = p.taps[j + r];
    const float* m = moments.data + (size_t(sy) * moments.width + x) * 3;
    s0 += t * __ldg(&m[0]);
    s1 += t * __ldg(&m[1]);
    s2 += t * __ldg(&m[2]);
  }
  const float mean = s1 / s0;
  const float variance = fmaxf(0.f, s2 / s0 - mean * mean);
  at(dst, x, y) = (at(src, x, y) - mean) / sqrtf(variance + p.epsilon * p.epsilon);
}

}  // namespace

cudaError_t launchNormalise(cudaStream_t s, Img dst, Img moments, Img src, Img mask, const NormaliseParams& p) {
  const dim3 block(32, 8), grid = grid2d(src.width, src.height, block);
  CS_LAUNCH(normaliseMomentsKernel, grid, block, 0, s, moments, src, mask, p);
  CS_LAUNCH(normaliseKernel, grid, block, 0, s, dst, moments, src, mask, p);
  return cudaGetLastError();
}

}  // namespace cs::cudak

// 3x3 median of u over the masked neighbours (cpu/median.cpp); even counts take the mean
// of the two middle values. Also the fused median + accumulate of the warp's last stages.
#include "warp_derivatives.cuh"

namespace cs::cudak {

namespace {

__device__ __forceinline__ void order(float& a, float& b) {
  const float lo = fminf(a, b), hi = fmaxf(a, b);
  a = lo, b = hi;
}

// The median of nine values by a 19-exchange network (the fifth smallest, exactly what
// sorting gives), in registers: the common case of a pixel whose neighbours are all masked.
__device__ __forceinline__ float median9(float p0, float p1, float p2, float p3, float p4, float p5, float p6, float p7,
                                         float p8) {
  order(p1, p2), order(p4, p5), order(p7, p8), order(p0, p1), order(p3, p4), order(p6, p7);
  order(p1, p2), order(p4, p5), order(p7, p8), order(p0, p3), order(p5, p8), order(p4, p7);
  order(p3, p6), order(p1, p4), order(p2, p5), order(p4, p7), order(p4, p2), order(p6, p4);
  order(p4, p2);
  return p4;
}

// u and the mask of a block's pixels and their one-pixel ring, in shared memory: every
// pixel reads nine of each, which from global memory cost more than the median itself.
constexpr int kBlockW = 32, kBlockH = 8;
constexpr int kRingW = kBlockW + 2, kRingH = kBlockH + 2;
constexpr int kRingRounds = (kRingW * kRingH + kBlockW * kBlockH - 1) / (kBlockW * kBlockH);

struct MedianTile {
  float u[kRingH][kRingW];
  bool masked[kRingH][kRingW];
};

// Loads every cell's value before storing any (one memory round trip for the block). u is
// loaded beside the mask, not after it; `beforeU` runs between the two (a kernel may wait
// there for the kernel that wrote u, having loaded the mask while it finished).
template <class BeforeU>
__device__ __forceinline__ void loadTile(MedianTile& t, const Img& src, const Img& mask, BeforeU beforeU) {
  const int tid = threadIdx.y * kBlockW + threadIdx.x;
  const int x0 = int(blockIdx.x) * kBlockW - 1, y0 = int(blockIdx.y) * kBlockH - 1;
  float value[kRingRounds];
  bool in[kRingRounds];
#pragma unroll
  for (int r = 0; r < kRingRounds; ++r) {
    const int k = tid + r * kBlockW * kBlockH;
    const int x = x0 + k % kRingW, y = y0 + k / kRingW;
    in[r] = k < kRingW * kRingH && inside(mask, x, y) && __ldg(&at(mask, x, y)) != 0.f;
  }
  beforeU();
#pragma unroll
  for (int r = 0; r < kRingRounds; ++r) {
    const int k = tid + r * kBlockW * kBlockH;
    const int x = x0 + k % kRingW, y = y0 + k / kRingW;
    value[r] = k < kRingW * kRingH && inside(mask, x, y) ? __ldg(&at(src, x, y)) : 0.f;
  }
#pragma unroll
  for (int r = 0; r < kRingRounds; ++r) value[r] = in[r] ? value[r] : 0.f;
#pragma unroll
  for (int r = 0; r < kRingRounds; ++r) {
    const int k = tid + r * kBlockW * kBlockH;
    if (k < kRingW * kRingH) {
      t.u[k / kRingW][k % kRingW] = value[r];
      t.masked[k / kRingW][k % kRingW] = in[r];
    }
  }
}

// The masked median of the thread's pixel (a masked one) from the tile.
__device__ __forceinline__ float maskedMedian(const MedianTile& t) {
  const int cx = threadIdx.x + 1, cy = threadIdx.y + 1;
  bool all = true;
#pragma unroll
  for (int dy = -1; dy <= 1; ++dy)
#pragma unroll
    for (int dx = -1; dx <= 1; ++dx) all = all && t.masked[cy + dy][cx + dx];
  if (all) {
    auto v = [&](int dx, int dy) { return t.u[cy + dy][cx + dx]; };
    return median9(v(-1, -1), v(0, -1), v(1, -1), v(-1, 0), v(0, 0), v(1, 0), v(-1, 1), v(0, 1), v(1, 1));
  }
  // Beside the mask's edge: insertion sort of the masked neighbours.
  float values[9];
  int n = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      if (t.masked[cy + dy][cx + dx]) values[n++] = t.u[cy + dy][cx + dx];
  for (int i = 1; i < n; ++i) {
    const float v = values[i];
    int j = i - 1;
    while (j >= 0 && values[j] > v) {
      values[j + 1] = values[j];
      --j;
    }
    values[j + 1] = v;
  }
  float upper = values[n / 2];
  if (n % 2 == 0) upper = 0.5f * (values[n / 2 - 1] + upper);
  return upper;
}

__global__ void __launch_bounds__(kBlockW* kBlockH) medianKernel(Img dst, Img src, Img mask) {
  beginKernel();
  __shared__ MedianTile t;
  loadTile(t, src, mask, [] {});
  __syncthreads();
  const int x = blockIdx.x * kBlockW + threadIdx.x, y = blockIdx.y * kBlockH + threadIdx.y;
  if (x >= dst.width || y >= dst.height) return;
  at(dst, x, y) = t.masked[threadIdx.y + 1][threadIdx.x + 1] ? maskedMedian(t) : at(src, x, y);
}

// accumulateKernel (accumulate.cu) reading u from the median computed here, and, with
// kNextWarp, the next warp's derivatives of the pixel.
template <bool kNextWarp>
__global__ void __launch_bounds__(kBlockW* kBlockH)
    medianAccumulateKernel(Img uOut, Img median, Img u, Img w, Img u0, Img tangent, Img mask, float duMax,
                           DataTermOut nextOut, DataTermIn next, bool afterPrimalDual) {
  // After a primal-dual kernel, which writes none of them, w, u0, the tangent and the mask
  // are loaded while it finishes (programmatic dependent launch); u after waiting for it.
  if (!afterPrimalDual) awaitPreviousKernel();
  __shared__ MedianTile t;
  const int x = blockIdx.x * kBlockW + threadIdx.x, y = blockIdx.y * kBlockH + threadIdx.y;
  const bool inside = x < u.width && y < u.height;
  // Loaded with the tile rather than after the median: one round trip to memory less.
  const AccumulateInputs inputs = inside ? loadAccumulateInputs(w, u0, tangent, x, y) : AccumulateInputs{};
  loadTile(t, u, mask, [&] {
    if (afterPrimalDual) awaitPreviousKernel();
    releaseNextKernel();
  });
  __syncthreads();
  if (!inside) return;
  const bool isMasked = t.masked[threadIdx.y + 1][threadIdx.x + 1];
  float uNew, wx = 0.f, wy = 0.f;
  if (!isMasked) {
    uNew = at(u, x, y);
    at(median, x, y) = at(uOut, x, y) = uNew;
  } else {
    const float m = maskedMedian(t);
    at(median, x, y) = m;
    uNew = accumulateFrom(inputs, uOut, w, x, y, m, duMax, wx, wy);
  }
  if (!kNextWarp) return;
  at(u0, x, y) = uNew;
  dataTermAt(nextOut, next, x, y, isMasked, wx, wy);
}

}  // namespace

cudaError_t launchMedian(cudaStream_t s, Img dst, Img src, Img mask) {
  const dim3 block(kBlockW, kBlockH);
  CS_LAUNCH(medianKernel, grid2d(dst.width, dst.height, block), block, 0, s, dst, src, mask);
  return cudaSuccess;
}

cudaError_t launchMedianAccumulate(cudaStream_t s, Img uOut, Img median, Img u, Img w, Img u0, Img tangent, Img mask,
                                   float duMax, const DataTermOut* nextOut, const DataTermIn* next,
                                   bool afterPrimalDual) {
  const dim3 block(kBlockW, kBlockH);
  const dim3 grid = grid2d(u.width, u.height, block);
  if (next)
    CS_LAUNCH(medianAccumulateKernel<true>, grid, block, 0, s, uOut, median, u, w, u0, tangent, mask, duMax, *nextOut,
              *next, afterPrimalDual);
  else
    CS_LAUNCH(medianAccumulateKernel<false>, grid, block, 0, s, uOut, median, u, w, u0, tangent, mask, duMax,
              DataTermOut{}, DataTermIn{}, afterPrimalDual);
  return cudaSuccess;
}

}  // namespace cs::cudak

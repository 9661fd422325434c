// Local contrast normalisation (cpu/normalise.cpp): a horizontal pass takes the masked,
// tap-weighted sums of 1, I and I^2 along each row; a vertical pass sums those over the
// column and writes (I - mean) / sqrt(max(0, var) + eps^2). One kernel does both for a
// tile of outputs through shared memory, which saves a launch and the row sums' round trip
// through global memory (12 bytes a pixel each way): the tile's src and mask with a halo
// of r pixels on every side, then the row sums of the tile's columns over its rows and the
// r rows above and below. It is instantiated per radius, so that the tap loops unroll.
// Radii whose halo does not fit a block's shared memory take two kernels instead, with the
// row sums in `moments`. Each thread adds its terms in the
// oracle's order (taps from -r to r) and the kernels are built without contraction
// (--fmad=false), with IEEE division and square root, so results agree with the oracle to
// the bit on the same inputs.
#include <array>
#include <utility>

#include "common.cuh"

namespace cs::cudak {

namespace {

// The tiled kernel's outputs per block. Tall, so that the 2r halo rows, whose row sums the
// blocks above and below take as well, are few next to the tile's own (at the default
// radius 12, 56 rows of row sums for 32 of outputs). Its kTileW x kBlockH threads take
// every kBlockH-th row of the tile and of the halo (on an H200, 16 rows of threads were
// faster than 8 or 32).
constexpr int kTileW = 32, kTileH = 32, kBlockH = 16;

// A block's shared memory for radius R: src and the mask (nonzero: masked) of its tile and
// halo, the tile's first output at [R][R], and the row sums of the tile's columns.
template <int R>
struct Tile {
  static constexpr int kRows = kTileH + 2 * R, kCols = kTileW + 2 * R;
  float s0[kRows][kTileW], s1[kRows][kTileW], s2[kRows][kTileW];
  float src[kRows][kCols];
  unsigned char mask[kRows][kCols];
};

// The largest radius whose tile fits the 48 KB a block may have without opting in to more.
constexpr int kMaxTiledRadius = 17;
static_assert(sizeof(Tile<kMaxTiledRadius>) <= 48 * 1024 && sizeof(Tile<kMaxTiledRadius + 1>) > 48 * 1024,
              "kMaxTiledRadius must be the largest radius whose tile fits");
static_assert(kMaxTiledRadius >= 12, "the default norm_sigma 4 (radius 12) must take the tiled kernel");

// src and the mask of the tile and halo, whose [0][0] is image pixel (x0, y0); outside
// the image the mask is 0 (masked()). src is read only where the mask is set: the passes
// use no other value.
template <int R>
__device__ void loadTile(Tile<R>& t, int x0, int y0, const Img& src, const Img& mask) {
  for (int hy = threadIdx.y; hy < t.kRows; hy += kBlockH)
    for (int hx = threadIdx.x; hx < t.kCols; hx += kTileW) {
      const int x = x0 + hx, y = y0 + hy;
      const bool in = masked(mask, x, y);
      t.mask[hy][hx] = in;
      t.src[hy][hx] = in ? __ldg(&src.data[size_t(y) * src.width + x]) : 0.f;
    }
}

// normaliseMomentsKernel's sums for column x of the tile, over the rows of tile and halo
// inside the image (the vertical pass skips the others); halo row hy is image row y0 + hy.
// Halo columns outside the image are unmasked, so skipped as the oracle skips them.
template <int R>
__device__ void rowSums(Tile<R>& t, int x, int y0, int width, int height, const NormaliseParams& p) {
  const int tx = threadIdx.x;
  if (x >= width) return;
  for (int hy = threadIdx.y; hy < t.kRows; hy += kBlockH) {
    if (y0 + hy < 0 || y0 + hy >= height) continue;
    float s0 = 0.f, s1 = 0.f, s2 = 0.f;
#pragma unroll
    for (int i = -R; i <= R; ++i) {  // the tap at offset i is at halo column tx + R + i
      if (!t.mask[hy][tx + R + i]) continue;
      const float w = p.taps[i + R], v = t.src[hy][tx + R + i];
      s0 += w;
      s1 += w * v;
      s2 += w * (v * v);
    }
    t.s0[hy][tx] = s0, t.s1[hy][tx] = s1, t.s2[hy][tx] = s2;
  }
}

// normaliseKernel for the tile's outputs in column x inside the image, from the row sums;
// the tile's row ty is image row y0 + ty, halo row ty + R.
template <int R>
__device__ void normaliseColumn(const Tile<R>& t, int x, int y0, const Img& dst, const NormaliseParams& p) {
  const int tx = threadIdx.x;
  if (x >= dst.width) return;
  for (int ty = threadIdx.y; ty < kTileH && y0 + ty < dst.height; ty += kBlockH) {
    const int y = y0 + ty;
    if (!t.mask[ty + R][tx + R]) {
      at(dst, x, y) = 0.f;
      continue;
    }
    float s0 = 0.f, s1 = 0.f, s2 = 0.f;
#pragma unroll
    for (int j = -R; j <= R; ++j) {
      if (y + j < 0 || y + j >= dst.height) continue;
      const float w = p.taps[j + R];
      s0 += w * t.s0[ty + R + j][tx];
      s1 += w * t.s1[ty + R + j][tx];
      s2 += w * t.s2[ty + R + j][tx];
    }
    const float mean = s1 / s0;
    const float variance = fmaxf(0.f, s2 / s0 - mean * mean);
    at(dst, x, y) = (t.src[ty + R][tx + R] - mean) / sqrtf(variance + p.epsilon * p.epsilon);
  }
}

// One block a kTileW x kTileH tile of dst; p.radius is R.
template <int R>
__global__ void normaliseTiledKernel(Img dst, Img src, Img mask, NormaliseParams p) {
  beginKernel();
  __shared__ Tile<R> t;
  const int x0 = blockIdx.x * kTileW, y0 = blockIdx.y * kTileH, x = x0 + threadIdx.x;
  loadTile(t, x0 - R, y0 - R, src, mask);
  __syncthreads();
  rowSums(t, x, y0 - R, src.width, src.height, p);
  __syncthreads();
  normaliseColumn(t, x, y0, dst, p);
}

using TiledKernel = void (*)(Img, Img, Img, NormaliseParams);
template <int... R>
constexpr std::array<TiledKernel, sizeof...(R)> tiledKernels(std::integer_sequence<int, R...>) {
  return {&normaliseTiledKernel<R>...};
}
// normaliseTiledKernel<r> at [r].
constexpr auto kTiledKernels = tiledKernels(std::make_integer_sequence<int, kMaxTiledRadius + 1>{});

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

// The tiled kernel leaves `moments` alone; radii above kMaxTiledRadius take the two kernels.
cudaError_t launchNormalise(cudaStream_t s, Img dst, Img moments, Img src, Img mask, const NormaliseParams& p) {
  if (p.radius <= kMaxTiledRadius) {
    const dim3 grid = grid2d(src.width, src.height, dim3(kTileW, kTileH));
    CS_LAUNCH(kTiledKernels[p.radius], grid, dim3(kTileW, kBlockH), 0, s, dst, src, mask, p);
    return cudaGetLastError();
  }
  const dim3 block(32, 8), grid = grid2d(src.width, src.height, block);
  CS_LAUNCH(normaliseMomentsKernel, grid, block, 0, s, moments, src, mask, p);
  CS_LAUNCH(normaliseKernel, grid, block, 0, s, dst, moments, src, mask, p);
  return cudaGetLastError();
}

}  // namespace cs::cudak

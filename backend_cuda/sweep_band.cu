// The band sweep (cpu/plane_sweep.cpp, "the band sweep"): a coarser full sweep proposes a
// hypothesis a pixel and the level scores only p.band (<= 32) hypotheses around it,
// channel k of every volume being hypothesis first + k. The full sweep's arithmetic
// (plane_sweep.cuh) in the oracle's order; built with --fmad=false like it.
#include <algorithm>
#include <climits>

#include "plane_sweep.cuh"

namespace cs::cudak {

namespace {

// sweepBandWarp: pixels of one row per block, as sweepWarp: each pixel's band start and
// ray are found once, then the block's threads walk the (pixel, hypothesis) pairs
// hypothesis-fastest, the volume's memory order.
constexpr int kWarpPixels = 32;
constexpr int kWarpThreads = 256;

// sweepBandCostKernel (radii past kMaxUnrolledRadius): a thread per (pixel, hypothesis),
// hypothesis-fastest, each summing its whole window. A pixel's lanes read the same mask,
// reference and band start (broadcasts) and consecutive channels of the volume (coalesced).
constexpr int kCostThreads = 128;
constexpr int kMaxUnrolledRadius = 3;  // windows up to 7x7: the tiled kernel below

// sweepBandCostTileKernel (radius <= kMaxUnrolledRadius): a block per tile of pixels stages
// the tile and its halo (mask and band start folded into one int, reference) in shared
// memory, then walks the tile's rows: each row's column partials once (kRowHypotheses),
// then its (pixel, hypothesis) pairs hypothesis-fastest.
constexpr int kTileX = 16, kTileY = 8;
constexpr int kTileThreads = 256;

// sweepBandSelect: a thread per pixel, a warp's 32 pixels staged together.
constexpr int kSelectThreads = 128;

// A coarse winner as a plane index, rounded half up (double); -1 for none.
__device__ int coarsePlane(const Img& coarseBest, const SweepParams& p, int cx, int cy) {
  const float q = at(coarseBest, cx, cy, 0);
  return q < 0.f ? -1 : int(floor(double(q) * double(p.planes - 1) / p.qMax + 0.5));
}

// The oracle's start of the band at pixel (x, y): centred on the coarse 3x3 neighbourhood's
// winners where they fit with kBandMargin to spare, else on the nearest coarse pixel's;
// -1 outside the mask or where the nearest coarse pixel found nothing.
__device__ int bandStart(const Img& coarseBest, const Img& mask, const SweepParams& p, float coarseScale, int x,
                         int y) {
  const int cx = min(coarseBest.width - 1, int((float(x) + 0.5f) * coarseScale));
  const int cy = min(coarseBest.height - 1, int((float(y) + 0.5f) * coarseScale));
  const int nearest = coarsePlane(coarseBest, p, cx, cy);
  if (!masked(mask, x, y) || nearest < 0) return -1;
  int lo = nearest, hi = nearest;
  for (int ny = max(cy - 1, 0); ny <= min(cy + 1, coarseBest.height - 1); ++ny)
    for (int nx = max(cx - 1, 0); nx <= min(cx + 1, coarseBest.width - 1); ++nx) {
      const int n = coarsePlane(coarseBest, p, nx, ny);
      if (n >= 0) lo = min(lo, n), hi = max(hi, n);
    }
  const int centre = hi - lo + 2 * kBandMargin <= p.band ? (lo + hi + 1) / 2 : nearest;
  return min(max(centre - p.band / 2, 0), p.planes - p.band);
}

__global__ void __launch_bounds__(kWarpThreads)
    sweepBandWarpKernel(Img volume, Img first, Img image, Img coarseBest, Img mask, SweepParams p, float coarseScale) {
  beginKernel();
  __shared__ V3 rays[kWarpPixels];
  __shared__ int starts[kWarpPixels];  // -1: no band, or no ray (every sample -1)
  const int x0 = blockIdx.x * kWarpPixels, y = blockIdx.y;
  const int count = min(kWarpPixels, volume.width - x0);
  if (int(threadIdx.x) < count) {
    const int x = x0 + threadIdx.x;
    const int start = bandStart(coarseBest, mask, p, coarseScale, x, y);
    at(first, x, y) = float(start);
    V3 ray{0, 0, 0};
    starts[threadIdx.x] = start >= 0 && cameraUnproject(p.cam, double(x), double(y), ray) ? start : -1;
    rays[threadIdx.x] = ray;
  }
  __syncthreads();
  // The block's pixels are adjacent in the row, so their bands form one contiguous run.
  float* const run = &at(volume, x0, y);
  for (int i = threadIdx.x; i < count * p.band; i += blockDim.x) {
    const int pixel = i / p.band, k = i % p.band, start = starts[pixel];
    float value = kNoSample;
    V2 px;
    if (start >= 0 && projectHypothesis(p.cam, rays[pixel], p.t, planeInverseDepth(p, double(start + k)), px))
      value = sampleBilinear(image, float(px.x), float(px.y));
    run[i] = value;
  }
}

// --- sweepBandCost ---

// What a thread reads: the row-major mask, reference and band starts, and the volume.
struct BandCostSource {
  const float* mask;
  const float* reference;
  const float* first;
  const float* volume;
  int width, height, band;
};

// The oracle's partials of column sx over dy = -r..r for hypothesis h: the valid samples
// (masked, in the image, h inside the sample's band, sampled) in order. Branch-free, as
// plane_sweep.cu's columnSums: an invalid sample adds +0 (a sum begun at +0 keeps its
// bits), out-of-image and out-of-band addresses are clamped.
__device__ __forceinline__ WindowSums bandColumnSums(const BandCostSource& c, int sx, int y, int r, int h) {
  WindowSums s{0.f, 0.f, 0.f, 0.f, 0.f, 0.f};
  const bool column = sx >= 0 && sx < c.width;
  const int cx = min(max(sx, 0), c.width - 1);
#pragma unroll
  for (int dy = -r; dy <= r; ++dy) {
    const int sy = y + dy;
    const int i = min(max(sy, 0), c.height - 1) * c.width + cx;
    const float m = __ldg(&c.mask[i]), a = __ldg(&c.reference[i]);
    const int there = int(__ldg(&c.first[i])), j = h - there;
    const float b = __ldg(&c.volume[size_t(i) * c.band + min(max(j, 0), c.band - 1)]);
    const bool valid =
        column && sy >= 0 && sy < c.height && m != 0.f && there >= 0 && j >= 0 && j < c.band && !(b < 0.f);
    addSample(s, valid, a, b);
  }
  return s;
}

// The thread's pixel (x, y), channel k and hypothesis h (-1: the pixel has no band or is
// outside the mask, its cost kNoCost); false past the image.
__device__ __forceinline__ bool bandCostWork(const Img& costs, const BandCostSource& src, int& x, int& y, int& h,
                                             float*& out) {
  const long long i = (long long)blockIdx.x * kCostThreads + threadIdx.x;
  if (i >= (long long)costs.width * costs.height * src.band) return false;
  const long long pixel = i / src.band;
  const int k = int(i - pixel * src.band);
  x = int(pixel % costs.width), y = int(pixel / costs.width);
  out = costs.data + i;
  const int start = int(__ldg(&src.first[pixel]));
  h = __ldg(&src.mask[pixel]) != 0.f && start >= 0 ? start + k : -1;
  return true;
}

// Radii past kMaxUnrolledRadius (the smaller ones take the tiled kernel below): a loop.
__global__ void __launch_bounds__(kCostThreads)
    sweepBandCostKernel(Img costs, Img reference, Img volume, Img first, Img mask, SweepParams p) {
  beginKernel();
  const BandCostSource src{mask.data, reference.data, first.data, volume.data, costs.width, costs.height, p.band};
  int x, y, h;
  float* out;
  if (!bandCostWork(costs, src, x, y, h, out)) return;
  if (h < 0) {
    *out = kNoCost;
    return;
  }
  const int r = p.radius;
  WindowSums s{0.f, 0.f, 0.f, 0.f, 0.f, 0.f};
  for (int dx = -r; dx <= r; ++dx) addColumn(s, bandColumnSums(src, x + dx, y, r, h));
  *out = windowCost(s, 2 * r + 1, p.flatVariance);
}

// A halo pixel of the tile: its reference and its band start, -1 where it adds nothing to
// a window (outside the image or the mask, or without a band).
struct TilePixel {
  float a;
  int there;
};

// Stages the tile at (x0, y0) with its halo of R: reference and band start a pixel.
template <int R>
__device__ __forceinline__ void stageBandTile(TilePixel* pixels, const BandCostSource& c, int x0, int y0) {
  constexpr int kW = kTileX + 2 * R, kH = kTileY + 2 * R;
  for (int i = threadIdx.x; i < kW * kH; i += blockDim.x) {
    const int sx = x0 - R + i % kW, sy = y0 - R + i / kW;
    TilePixel t{0.f, -1};
    if (sx >= 0 && sx < c.width && sy >= 0 && sy < c.height) {
      const int g = sy * c.width + sx, there = int(__ldg(&c.first[g]));
      t.a = __ldg(&c.reference[g]);
      if (__ldg(&c.mask[g]) != 0.f && there >= 0) t.there = there;
    }
    pixels[i] = t;
  }
}

// The lowest and highest band start among a tile row's own pixels (lo > hi: none has a band).
template <int R>
__device__ __forceinline__ void rowStarts(const TilePixel* pixels, int ty, int& lo, int& hi) {
  constexpr int kW = kTileX + 2 * R;
  lo = INT_MAX, hi = -1;
#pragma unroll
  for (int tx = 0; tx < kTileX; ++tx) {
    const int there = pixels[(ty + R) * kW + tx + R].there;
    if (there >= 0) lo = min(lo, there), hi = max(hi, there);
  }
}

// The oracle's partials of halo column c of tile row ty for hypothesis h, from the staged
// pixels and the volume (each sample is read by the 2R + 1 rows around it: L1 hits).
template <int R>
__device__ __forceinline__ WindowSums tileColumnSums(const TilePixel* pixels, const BandCostSource& src, int x0, int y0,
                                                     int ty, int c, int h) {
  constexpr int kW = kTileX + 2 * R;
  const int sx = min(max(x0 - R + c, 0), src.width - 1);
  WindowSums col{0.f, 0.f, 0.f, 0.f, 0.f, 0.f};
#pragma unroll
  for (int dy = -R; dy <= R; ++dy) {
    const TilePixel t = pixels[(ty + R + dy) * kW + c];
    const int sy = min(max(y0 + ty + dy, 0), src.height - 1), j = h - t.there;
    const float b = __ldg(&src.volume[(size_t(sy) * src.width + sx) * src.band + min(max(j, 0), src.band - 1)]);
    // An invalid sample adds +0 (a sum begun at +0 keeps its bits), as bandColumnSums.
    addSample(col, t.there >= 0 && j >= 0 && j < src.band && !(b < 0.f), t.a, b);
  }
  return col;
}

// The column partials of one tile row, kept for the hypotheses the row's bands span: the
// windows of neighbouring pixels share 2R of their 2R + 1 columns, and where their bands
// start alike (smooth surfaces), the same hypotheses too, so each partial is summed once
// instead of once per window. Field f of column c, hypothesis lo + k at (f * kW + c) *
// kRowHypotheses + k: a warp's lanes (consecutive k) read consecutive words.
constexpr int kRowHypotheses = 64;

template <int R>
__global__ void __launch_bounds__(kTileThreads)
    sweepBandCostTileKernel(Img costs, Img reference, Img volume, Img first, Img mask, SweepParams p) {
  beginKernel();
  constexpr int kW = kTileX + 2 * R, kH = kTileY + 2 * R, kFields = 6;
  __shared__ TilePixel pixels[kW * kH];
  __shared__ float partials[kFields * kW * kRowHypotheses];
  const BandCostSource src{mask.data, reference.data, first.data, volume.data, costs.width, costs.height, p.band};
  const int x0 = blockIdx.x * kTileX, y0 = blockIdx.y * kTileY, band = p.band;
  stageBandTile<R>(pixels, src, x0, y0);
  __syncthreads();
  for (int ty = 0; ty < kTileY && y0 + ty < costs.height; ++ty) {
    int lo, hi;
    rowStarts<R>(pixels, ty, lo, hi);  // the same in every thread: the branches below are uniform
    const int span = hi - lo + band;
    const bool cached = lo <= hi && span <= kRowHypotheses;
    if (cached) {
      for (int i = threadIdx.x; i < kW * span; i += blockDim.x) {
        const int c = i / span, k = i - c * span;
        const WindowSums col = tileColumnSums<R>(pixels, src, x0, y0, ty, c, lo + k);
        const float fields[kFields] = {col.n, col.s0, col.s1, col.s00, col.s11, col.s01};
#pragma unroll
        for (int f = 0; f < kFields; ++f) partials[(f * kW + c) * kRowHypotheses + k] = fields[f];
      }
      __syncthreads();
    }
    const int y = y0 + ty;
    for (int i = threadIdx.x; i < kTileX * band; i += blockDim.x) {
      const int tx = i / band, k = i - tx * band, x = x0 + tx;
      if (x >= costs.width) continue;
      const int start = pixels[(ty + R) * kW + tx + R].there;
      float cost = kNoCost;
      if (start >= 0) {
        // The oracle's order: dx outer, each column's partials over dy, then into the window's.
        WindowSums s{0.f, 0.f, 0.f, 0.f, 0.f, 0.f};
        const int h = start + k;
        if (cached) {
#pragma unroll
          for (int dx = -R; dx <= R; ++dx) {
            const float* const column = &partials[(tx + R + dx) * kRowHypotheses + h - lo];
            constexpr int kField = kW * kRowHypotheses;
            addColumn(s, {column[0], column[kField], column[2 * kField], column[3 * kField], column[4 * kField],
                          column[5 * kField]});
          }
        } else {  // bands too far apart in this row to share: each window alone
#pragma unroll 1
          for (int dx = -R; dx <= R; ++dx) addColumn(s, tileColumnSums<R>(pixels, src, x0, y0, ty, tx + R + dx, h));
        }
        cost = windowCost(s, 2 * R + 1, p.flatVariance);
      }
      costs.data[(size_t(y) * costs.width + x) * band + k] = cost;
    }
    if (cached) __syncthreads();  // the next row's partials overwrite these
  }
}

// --- sweepBandAggregate ---

// One walk along a scanline: step i's pixel is start + i * delta (from the line's far end,
// delta negative, when walking backward).
struct BandWalk {
  const float* costs;
  const float* first;
  const float* mask;
  float* out;
  int start, delta, length, band;
  float p1, p2;
  // Clamped to the line: a chunk's loads past its end read the last pixel again, unused.
  __device__ int pixel(int step) const { return start + min(step, length - 1) * delta; }
};

// The steps whose inputs are loaded together, a chunk ahead of their use: a step is a short
// chain of shuffles and compares, so every step's own branch, address arithmetic or wait
// for a load would dominate it. Lane k holds hypothesis k's cost at each step of the chunk,
// lane i the mask and band start of step i (raw: converting them on load would wait for it).
constexpr int kBandChunk = 32;
struct BandChunk {
  float cost[kBandChunk];
  float mask, first;
};

// Lane k's path cost at the previous pixel (hypothesis previousFirst + k).
struct BandPath {
  float previous, previousMin;
  int previousFirst;
  bool havePrevious;
};

__device__ __forceinline__ void loadBandChunk(BandChunk& c, const BandWalk& w, int step0) {
  const int lane = threadIdx.x & 31, k = min(lane, w.band - 1);  // spare lanes: a hypothesis they never use
#pragma unroll
  for (int d = 0; d < kBandChunk; ++d) c.cost[d] = __ldg(&w.costs[size_t(w.pixel(step0 + d)) * w.band + k]);
  const int pixel = w.pixel(step0 + lane);
  c.mask = __ldg(&w.mask[pixel]);
  c.first = __ldg(&w.first[pixel]);
}

// Lane i's band start of the chunk's step i, -1 outside the mask or without a band.
__device__ __forceinline__ int chunkStart(const BandChunk& c) {
  const int start = int(c.first);
  return c.mask != 0.f && start >= 0 ? start : -1;
}

// The minimum over the warp, exact in any order. The next step waits for it, so on sm_80
// and newer it is one integer reduction instead of a five-shuffle butterfly: a float's bits
// with the magnitude flipped for negatives compare as signed integers as the floats do
// (a NaN, which fminf would skip, never arises from the capped costs).
__device__ __forceinline__ float bandMin(float value) {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 800
  int key = __float_as_int(value);
  key ^= (key >> 31) & 0x7fffffff;
  key = __reduce_min_sync(0xffffffffu, key);
  return __int_as_float(key ^ ((key >> 31) & 0x7fffffff));
#else
  for (int offset = 16; offset > 0; offset /= 2) value = fminf(value, __shfl_xor_sync(0xffffffffu, value, offset));
  return value;
#endif
}

// One step at band start `first` (-1: none), branch-free so that the scheduler overlaps the
// steps' independent work. Lane k is hypothesis h = first + k; the previous pixel's L(h),
// L(h -+ 1) come from lanes j, j -+ 1 (j = k + first - previousFirst) where its band holds
// them, and the oracle's minima run in its order: m + p2, then L(h), L(h - 1) + p1,
// L(h + 1) + p1; then the step's minimum over the band. A pixel outside the mask or
// without a band adds nothing to the oracle's 0 and restarts the path: L = 0 there.
__device__ __forceinline__ void bandWalkStep(BandPath& s, float cost, int first, const BandWalk& w, int step) {
  const int lane = threadIdx.x & 31, j = lane + first - s.previousFirst;
  auto held = [&](int i) { return unsigned(i) < unsigned(w.band); };
  // A shuffle reads lane i mod 32: an index the band does not hold reads a value left unused.
  const float here = __shfl_sync(0xffffffffu, s.previous, j);
  const float below = __shfl_sync(0xffffffffu, s.previous, j - 1);
  const float above = __shfl_sync(0xffffffffu, s.previous, j + 1);
  const float c = stdMin(cost, kCostCap);
  float v = s.previousMin + w.p2;
  if (held(j)) v = stdMin(here, v);
  if (held(j - 1)) v = stdMin(v, below + w.p1);
  if (held(j + 1)) v = stdMin(v, above + w.p1);
  const float path = c + v - s.previousMin;
  const float l = first < 0 ? 0.f : s.havePrevious ? path : c;
  if (lane < w.band && step < w.length) w.out[size_t(w.pixel(step)) * w.band + lane] = l;
  s.previous = l;
  s.previousMin = bandMin(lane < w.band ? l : INFINITY);
  s.previousFirst = first;
  s.havePrevious = first >= 0;
}

// A whole walk, chunk by chunk, the next chunk's inputs loading while this one's steps run.
__device__ void bandWalkLine(const BandWalk& w) {
  BandPath s{0.f, 0.f, 0, false};
  BandChunk chunk, next;
  loadBandChunk(chunk, w, 0);
  for (int step0 = 0; step0 < w.length; step0 += kBandChunk) {
    if (step0 + kBandChunk < w.length) loadBandChunk(next, w, step0 + kBandChunk);
    const int starts = chunkStart(chunk);
#pragma unroll
    for (int d = 0; d < kBandChunk; ++d)
      bandWalkStep(s, chunk.cost[d], __shfl_sync(0xffffffffu, starts, d), w, step0 + d);
    chunk = next;
  }
}

// One warp per direction of a line, every line and direction at once (blockIdx.y: +x,
// -x, +y, -y), each into its own buffer: `aggregated` for +x, slices of `spare` for the
// rest; sweepBandCombineKernel then adds them in the oracle's order.
__global__ void __launch_bounds__(32)
    sweepBandDirectionKernel(Img aggregated, Img spare, Img costs, Img first, Img mask, SweepParams p) {
  beginKernel();
  const int direction = blockIdx.y, line = blockIdx.x, width = costs.width;
  const bool rows = direction < 2;
  if (line >= (rows ? costs.height : width)) return;
  const size_t size = size_t(aggregated.width) * aggregated.height * aggregated.channels;
  float* const out = direction == 0 ? aggregated.data : spare.data + size * size_t(direction - 1);
  const bool forward = direction % 2 == 0;
  const int length = rows ? width : costs.height, stride = rows ? 1 : width;
  const int start = (rows ? line * width : line) + (forward ? 0 : (length - 1) * stride);
  const BandWalk w{costs.data, first.data, mask.data, out, start, forward ? stride : -stride,
                   length,     p.band,     p.p1,      p.p2};
  bandWalkLine(w);
}

// aggregated = (((0 + L+x) + L-x) + L+y) + L-y, the oracle's sum (0 outside the mask).
__global__ void sweepBandCombineKernel(Img aggregated, Img spare) {
  beginKernel();
  const size_t n = size_t(aggregated.width) * aggregated.height * aggregated.channels;
  const size_t stride = size_t(gridDim.x) * blockDim.x;
  for (size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x; i < n; i += stride)
    aggregated.data[i] = (((0.f + aggregated.data[i]) + spare.data[i]) + spare.data[i + n]) + spare.data[i + 2 * n];
}

// --- sweepBandSelect ---

// The oracle's select within the band: the first hypothesis minimising `aggregated` among
// the scored, refused on an inner edge of the band (the full range continues past it, so
// the minimum may lie beyond), refined by the parabola. A thread a pixel; each warp first
// copies its 32 pixels' bands (contiguous in memory) into shared memory with coalesced
// loads, transposed so that each lane then reads its own pixel's row without bank conflicts.
__global__ void __launch_bounds__(kSelectThreads)
    sweepBandSelectKernel(Img best, Img aggregated, Img costs, Img first, Img mask, SweepParams p) {
  beginKernel();
  __shared__ float sharedA[kSelectThreads / 32][32][33], sharedC[kSelectThreads / 32][32][33];
  const int n = p.band, lane = threadIdx.x & 31, warp = threadIdx.x / 32;
  const long long pixels = (long long)best.width * best.height;
  const long long warpFirst = (long long)blockIdx.x * kSelectThreads + warp * 32;
  if (warpFirst >= pixels) return;  // whole warps
  const long long base = warpFirst * n, end = pixels * n;
  for (int i = lane; i < 32 * n; i += 32) {
    const bool inside = base + i < end;
    sharedA[warp][i / n][i % n] = inside ? __ldg(&aggregated.data[base + i]) : 0.f;
    sharedC[warp][i / n][i % n] = inside ? __ldg(&costs.data[base + i]) : kNoCost;
  }
  __syncwarp();
  const long long pixel = warpFirst + lane;
  if (pixel >= pixels) return;
  const int x = int(pixel % best.width), y = int(pixel / best.width);
  const int start = int(at(first, x, y));
  float q = -1.f, winnerCost = kNoCost;
  if (masked(mask, x, y) && start >= 0) {
    const float* const a = sharedA[warp][lane];
    const float* const c = sharedC[warp][lane];
    int winner = -1;
    float lowest = 0.f;
    for (int k = 0; k < n; ++k)
      if (c[k] < kNoCost && (winner < 0 || a[k] < lowest)) winner = k, lowest = a[k];
    const bool edge = (winner == 0 && start > 0) || (winner == n - 1 && start + n < p.planes);
    if (winner >= 0 && !edge) {
      q = refinedInverseDepth(a, c, n, start, winner, p);
      winnerCost = c[winner];
    }
  }
  at(best, x, y, 0) = q;
  at(best, x, y, 1) = winnerCost;
}

bool bandValid(const SweepParams& p) { return p.band >= 2 && p.band <= kMaxSweepBand && p.band <= p.planes; }

}  // namespace

cudaError_t launchSweepBandWarp(cudaStream_t s, Img volume, Img first, Img image, Img coarseBest, Img mask,
                                const SweepParams& p, float coarseScale) {
  if (!bandValid(p)) return cudaErrorInvalidValue;
  const dim3 grid((volume.width + kWarpPixels - 1) / kWarpPixels, volume.height);
  CS_LAUNCH(sweepBandWarpKernel, grid, kWarpThreads, 0, s, volume, first, image, coarseBest, mask, p, coarseScale);
  return cudaGetLastError();
}

cudaError_t launchSweepBandCost(cudaStream_t s, Img costs, Img reference, Img volume, Img first, Img mask,
                                const SweepParams& p) {
  if (!bandValid(p)) return cudaErrorInvalidValue;
  const long long threads = (long long)costs.width * costs.height * p.band;
  const dim3 grid(unsigned((threads + kCostThreads - 1) / kCostThreads));
  const dim3 tiles((costs.width + kTileX - 1) / kTileX, (costs.height + kTileY - 1) / kTileY);
  switch (p.radius) {
    case 0:
      CS_LAUNCH(sweepBandCostTileKernel<0>, tiles, kTileThreads, 0, s, costs, reference, volume, first, mask, p);
      break;
    case 1:
      CS_LAUNCH(sweepBandCostTileKernel<1>, tiles, kTileThreads, 0, s, costs, reference, volume, first, mask, p);
      break;
    case 2:
      CS_LAUNCH(sweepBandCostTileKernel<2>, tiles, kTileThreads, 0, s, costs, reference, volume, first, mask, p);
      break;
    case 3:
      CS_LAUNCH(sweepBandCostTileKernel<3>, tiles, kTileThreads, 0, s, costs, reference, volume, first, mask, p);
      break;
    default:
      CS_LAUNCH(sweepBandCostKernel, grid, kCostThreads, 0, s, costs, reference, volume, first, mask, p);
  }
  static_assert(kMaxUnrolledRadius == 3, "one case per unrolled radius");
  return cudaGetLastError();
}

cudaError_t launchSweepBandAggregate(cudaStream_t s, Img aggregated, Img spare, Img costs, Img first, Img mask,
                                     const SweepParams& p) {
  if (!bandValid(p)) return cudaErrorInvalidValue;
  const dim3 grid(unsigned(max(costs.width, costs.height)), 4);
  CS_LAUNCH(sweepBandDirectionKernel, grid, dim3(32), 0, s, aggregated, spare, costs, first, mask, p);
  const size_t n = size_t(aggregated.width) * aggregated.height * aggregated.channels;
  const unsigned blocks = unsigned(std::min<size_t>((n + 255) / 256, 4096));
  CS_LAUNCH(sweepBandCombineKernel, dim3(blocks), dim3(256), 0, s, aggregated, spare);
  return cudaGetLastError();
}

cudaError_t launchSweepBandSelect(cudaStream_t s, Img best, Img aggregated, Img costs, Img first, Img mask,
                                  const SweepParams& p) {
  if (!bandValid(p)) return cudaErrorInvalidValue;
  const long long pixels = (long long)best.width * best.height;
  const dim3 grid(unsigned((pixels + kSelectThreads - 1) / kSelectThreads));
  CS_LAUNCH(sweepBandSelectKernel, grid, kSelectThreads, 0, s, best, aggregated, costs, first, mask, p);
  return cudaGetLastError();
}

}  // namespace cs::cudak

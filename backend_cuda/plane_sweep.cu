// Plane-sweep initialisation (cpu/plane_sweep.cpp): spheres of constant inverse depth
// around the reference camera, swept through the camera model, scored by ZNCC, aggregated
// semi-globally, chosen winner-take-all and checked left against right. Geometry in double
// through the device camera models, intensities and costs in float, every sum in the
// oracle's order (the kernels are built with --fmad=false, so floats match bit for bit).
#include <algorithm>

#include "plane_sweep.cuh"

namespace cs::cudak {

namespace {

// sweepWarp: pixels of one row per block. Their rays are unprojected once (the iterative
// inverse models are the expensive part) and the block's threads then walk the
// (pixel, plane) pairs plane-fastest, which is the volume's memory order: writes coalesce.
constexpr int kWarpPixels = 32;
constexpr int kWarpThreads = 256;

// sweepCost: each thread owns one plane k of a run of kCostRun pixels of a row, the
// (run, plane) pairs flattened as run * planes + k so that a warp's threads are
// consecutive planes (its volume reads and cost writes coalesce). The thread walks its run
// keeping the last 2r+1 column partials in registers: one new column per output instead
// of a whole window (hence the oracle's column-by-column sums). Measured (H100 80GB HBM3,
// T265 pair, both views): 0.79 / 0.14 ms at levels 1 / 2 (131 / 66 planes) against 2.11 /
// 0.28 for a thread per (pixel, plane) summing its whole window; issuing the next
// column's loads before an output's arithmetic measured the same (0.78 / 0.14).
constexpr int kCostThreads = 128;
constexpr int kCostRun = 32;
constexpr int kMaxRingRadius = 4;  // radii with a register ring; wider windows sum afresh

// sweepAggregate: one warp per direction of a scanline, lane l holding planes l, l + 32,
// ... in registers (J = planes / 32 rounded up, templated), neighbours by shuffles, the
// previous step's minimum by a butterfly, the costs loaded up to 11 steps ahead: no
// barrier in a step. The four directions walk at once into their own buffers and a
// second launch adds them in the oracle's order. Measured (same pair, both views): 1.11 /
// 0.18 ms at levels 1 / 2, against 2.14 / 0.33 for a block per line (a thread per plane,
// a barrier a step) and 1.18 / 0.28 for two warps per line meeting in the middle (rows,
// then columns adding into the rows' sum: less memory traffic, twice the chain of
// dependent steps). Costs capped at kCostCap (plane_sweep.cuh).

// sweepSelect: one warp per pixel, lanes over the planes, so the reads of a pixel's
// planes coalesce.
constexpr int kSelectThreads = 256;
constexpr int kSelectPixels = kSelectThreads / 32;

__global__ void __launch_bounds__(kWarpThreads) sweepWarpKernel(Img volume, Img image, Img mask, SweepParams p) {
  beginKernel();
  __shared__ V3 rays[kWarpPixels];
  __shared__ bool usable[kWarpPixels];
  const int x0 = blockIdx.x * kWarpPixels, y = blockIdx.y;
  const int count = min(kWarpPixels, volume.width - x0);
  if (int(threadIdx.x) < count) {
    const int x = x0 + threadIdx.x;
    V3 ray{0, 0, 0};
    usable[threadIdx.x] = masked(mask, x, y) && cameraUnproject(p.cam, double(x), double(y), ray);
    rays[threadIdx.x] = ray;
  }
  __syncthreads();
  // The block's pixels are adjacent in the row, so their planes form one contiguous run.
  float* const run = &at(volume, x0, y);
  for (int i = threadIdx.x; i < count * p.planes; i += blockDim.x) {
    const int pixel = i / p.planes, k = i % p.planes;
    float value = kNoSample;
    V2 px;
    if (usable[pixel] && projectHypothesis(p.cam, rays[pixel], p.t, planeInverseDepth(p, k), px))
      value = sampleBilinear(image, float(px.x), float(px.y));
    run[i] = value;
  }
}

// What a thread reads: the row-major mask and reference, and the volume at its plane.
struct CostSource {
  const float* mask;
  const float* reference;
  const float* volume;  // + k: the thread's plane
  int width, height, planes;
};

// The oracle's partials of column sx over dy = -r..r: its valid samples (masked, in the
// image, the hypothesis sampled) in order. Branch-free, every load issued at once: an
// invalid sample adds +0, which leaves a sum begun at +0 unchanged bit for bit (under
// round-to-nearest such a sum never becomes -0). Out-of-image addresses are clamped.
__device__ __forceinline__ WindowSums columnSums(const CostSource& c, int sx, int y, int r) {
  WindowSums s{0.f, 0.f, 0.f, 0.f, 0.f, 0.f};
  const bool column = sx >= 0 && sx < c.width;
  const int cx = min(max(sx, 0), c.width - 1);
#pragma unroll
  for (int dy = -r; dy <= r; ++dy) {
    const int sy = y + dy;
    const int j = min(max(sy, 0), c.height - 1) * c.width + cx;
    const float m = __ldg(&c.mask[j]), b = __ldg(&c.volume[size_t(j) * c.planes]), a = __ldg(&c.reference[j]);
    const bool valid = column && sy >= 0 && sy < c.height && m != 0.f && !(b < 0.f);
    addSample(s, valid, a, b);
  }
  return s;
}

// The thread's plane k and run of pixels [x0, x1) of row blockIdx.y; false past the row.
__device__ __forceinline__ bool costWork(const Img& costs, int planes, CostSource& src, int& x0, int& x1, float*& out) {
  const int i = blockIdx.x * kCostThreads + threadIdx.x, run = i / planes, k = i - run * planes;
  x0 = run * kCostRun;
  if (x0 >= costs.width) return false;
  x1 = min(x0 + kCostRun, costs.width);
  src.volume += k;
  out = costs.data + size_t(blockIdx.y) * costs.width * planes + k;
  return true;
}

// Radius R (<= kMaxRingRadius): the last 2R+1 column partials in a register ring, one new
// column per output, summed in dx order (the oracle's order).
template <int R>
__global__ void __launch_bounds__(kCostThreads)
    sweepCostKernel(Img costs, Img reference, Img volume, Img mask, SweepParams p) {
  beginKernel();
  constexpr int kSide = 2 * R + 1;
  CostSource src{mask.data, reference.data, volume.data, costs.width, costs.height, p.planes};
  int x0, x1;
  float* out;
  if (!costWork(costs, p.planes, src, x0, x1, out)) return;
  const int y = blockIdx.y;
  WindowSums ring[kSide];
#pragma unroll
  for (int c = 0; c + 1 < kSide; ++c) ring[c] = columnSums(src, x0 - R + c, y, R);
  for (int x = x0; x < x1; ++x) {
    ring[kSide - 1] = columnSums(src, x + R, y, R);
    WindowSums s{0.f, 0.f, 0.f, 0.f, 0.f, 0.f};
#pragma unroll
    for (int c = 0; c < kSide; ++c) addColumn(s, ring[c]);
    const bool inside = __ldg(&mask.data[y * costs.width + x]) != 0.f;
    out[size_t(x) * p.planes] = inside ? windowCost(s, kSide, p.flatVariance) : kNoCost;
#pragma unroll
    for (int c = 0; c + 1 < kSide; ++c) ring[c] = ring[c + 1];
  }
}

// Larger radii: each window's columns summed afresh (the same order, no ring).
__global__ void __launch_bounds__(kCostThreads)
    sweepCostWideKernel(Img costs, Img reference, Img volume, Img mask, SweepParams p) {
  beginKernel();
  CostSource src{mask.data, reference.data, volume.data, costs.width, costs.height, p.planes};
  int x0, x1;
  float* out;
  if (!costWork(costs, p.planes, src, x0, x1, out)) return;
  const int y = blockIdx.y, r = p.radius;
  for (int x = x0; x < x1; ++x) {
    WindowSums s{0.f, 0.f, 0.f, 0.f, 0.f, 0.f};
    for (int dx = -r; dx <= r; ++dx) addColumn(s, columnSums(src, x + dx, y, r));
    const bool inside = __ldg(&mask.data[y * costs.width + x]) != 0.f;
    out[size_t(x) * p.planes] = inside ? windowCost(s, 2 * r + 1, p.flatVariance) : kNoCost;
  }
}

// --- sweepAggregate ---

// One walk along a scanline: step i's pixel is start + i * stride, from the line's far
// end when walking backward; its path costs L go to `out`.
struct Walk {
  const float* costs;
  const float* mask;
  float* out;
  size_t start, stride;
  int length, planes, maskChannels;
  bool forward;
  float p1, p2;
  __device__ size_t pixel(int step) const { return start + size_t(forward ? step : length - 1 - step) * stride; }
};

// One step's inputs, loaded Ring::kSlots - 1 steps ahead.
template <int J>
struct StepIn {
  float cost[J];
  float mask;  // compared when the step runs: a compare at load time would wait for the load
};

// A walk's path costs: lane l holds planes l, l + 32, ... (J chunks of 32).
template <int J>
struct PathState {
  float previous[J];
  float previousMin;
  bool havePrevious;
};

// Steps loaded ahead + 1: a step is a few shuffles long, a load from memory about a
// microsecond under this load; the ring's registers (J + 1 per slot) bound it.
template <int J>
struct Ring {
  static constexpr int kSlots = 60 / J < 2 ? 2 : 60 / J > 12 ? 12 : 60 / J;
};

template <int J>
__device__ __forceinline__ void loadStep(StepIn<J>& in, const Walk& w, size_t pixel) {
  const int lane = threadIdx.x & 31;
  in.mask = __ldg(&w.mask[pixel * w.maskChannels]);
  const size_t row = pixel * w.planes;
#pragma unroll
  for (int j = 0; j < J; ++j) {
    // Spare lanes read a plane they never use: a select here would wait for the load.
    in.cost[j] = __ldg(&w.costs[row + min(lane + 32 * j, w.planes - 1)]);
  }
}

// The oracle's step for the lane's planes, l = min(C, cap) + min(L(k), L(k -+ 1) + p1,
// minL + p2) - minL; the neighbours by shuffles (lane 0's k - 1 is the previous chunk's
// lane 31, lane 31's k + 1 the next chunk's lane 0). Returns the step's minimum over the
// planes (a butterfly of minima: exact in any order).
template <int J>
__device__ __forceinline__ float pathStep(const PathState<J>& s, const float (&cost)[J], float (&l)[J], const Walk& w) {
  const int lane = threadIdx.x & 31;
  float left[J], right[J];
#pragma unroll
  for (int j = 0; j < J; ++j) {
    left[j] = __shfl_up_sync(0xffffffffu, s.previous[j], 1);
    right[j] = __shfl_down_sync(0xffffffffu, s.previous[j], 1);
  }
#pragma unroll
  for (int j = 0; j + 1 < J; ++j) {
    const float last = __shfl_sync(0xffffffffu, s.previous[j], 31),
                first = __shfl_sync(0xffffffffu, s.previous[j + 1], 0);
    if (lane == 0) left[j + 1] = last;
    if (lane == 31) right[j] = first;
  }
  float lowest = INFINITY;
#pragma unroll
  for (int j = 0; j < J; ++j) {
    const int k = lane + 32 * j;
    const float c = stdMin(cost[j], kCostCap);
    float v = stdMin(s.previous[j], s.previousMin + w.p2);
    if (k > 0) v = stdMin(v, left[j] + w.p1);
    if (k + 1 < w.planes) v = stdMin(v, right[j] + w.p1);
    l[j] = s.havePrevious ? c + v - s.previousMin : c;
    if (k < w.planes) lowest = fminf(lowest, l[j]);
  }
  for (int offset = 16; offset > 0; offset /= 2) lowest = fminf(lowest, __shfl_xor_sync(0xffffffffu, lowest, offset));
  return lowest;
}

// One step of a walk (its branches are the whole warp's). Outside the mask the oracle adds
// nothing to its 0 and restarts the path: L = 0 there.
template <int J>
__device__ __forceinline__ void walkStep(PathState<J>& s, const StepIn<J>& in, const Walk& w, size_t pixel) {
  const int lane = threadIdx.x & 31;
  float* const out = w.out + pixel * w.planes;
  if (in.mask == 0.f) {
    s.havePrevious = false;
#pragma unroll
    for (int j = 0; j < J; ++j)
      if (lane + 32 * j < w.planes) out[lane + 32 * j] = 0.f;
    return;
  }
  float l[J];
  const float lowest = pathStep(s, in.cost, l, w);
#pragma unroll
  for (int j = 0; j < J; ++j) {
    if (lane + 32 * j < w.planes) out[lane + 32 * j] = l[j];
    s.previous[j] = l[j];
  }
  s.previousMin = lowest;
  s.havePrevious = true;
}

// A whole walk. The ring's slot for step + slots - 1 is the one the previous step
// consumed, so no slot is read and refilled in the same step and each load stays in
// flight in its own registers (no register moves waiting on it).
template <int J>
__device__ void walkLine(const Walk& w) {
  constexpr int kSlots = Ring<J>::kSlots;
  PathState<J> s{};
  StepIn<J> ring[kSlots];
#pragma unroll
  for (int d = 0; d + 1 < kSlots; ++d)
    if (d < w.length) loadStep<J>(ring[d], w, w.pixel(d));
  for (int step0 = 0; step0 < w.length; step0 += kSlots) {
#pragma unroll
    for (int d = 0; d < kSlots; ++d) {
      const int step = step0 + d;
      if (step >= w.length) break;
      if (step + kSlots - 1 < w.length) loadStep<J>(ring[(d + kSlots - 1) % kSlots], w, w.pixel(step + kSlots - 1));
      walkStep<J>(s, ring[d], w, w.pixel(step));
    }
  }
}

// One warp per direction of a line, every line and direction at once (blockIdx.y: +x,
// -x, +y, -y), each into its own buffer: `aggregated` for +x, slices of `spare` for the
// rest; sweepCombineKernel then adds them in the oracle's order.
__device__ Img directionBuffer(const Img& aggregated, const Img& spare, int direction) {
  if (direction == 0) return aggregated;
  const size_t size = size_t(aggregated.width) * aggregated.height * aggregated.channels;
  return Img{spare.data + size * size_t(direction - 1), aggregated.width, aggregated.height, aggregated.channels};
}

template <int J>
__global__ void __launch_bounds__(32)
    sweepDirectionKernel(Img aggregated, Img spare, Img costs, Img mask, SweepParams p) {
  beginKernel();
  const int direction = blockIdx.y, line = blockIdx.x, width = costs.width;
  const bool rows = direction < 2;
  if (line >= (rows ? costs.height : width)) return;
  Walk w{costs.data,
         mask.data,
         directionBuffer(aggregated, spare, direction).data,
         0,
         0,
         0,
         p.planes,
         mask.channels,
         direction % 2 == 0,
         p.p1,
         p.p2};
  w.start = rows ? size_t(line) * width : size_t(line);
  w.stride = rows ? 1 : size_t(width);
  w.length = rows ? width : costs.height;
  walkLine<J>(w);
}

// aggregated = (((0 + L+x) + L-x) + L+y) + L-y, the oracle's sum (0 outside the mask).
__global__ void sweepCombineKernel(Img aggregated, Img spare) {
  beginKernel();
  const size_t n = size_t(aggregated.width) * aggregated.height * aggregated.channels;
  for (size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x; i < n; i += size_t(gridDim.x) * blockDim.x)
    aggregated.data[i] = (((0.f + aggregated.data[i]) + spare.data[i]) + spare.data[i + n]) + spare.data[i + 2 * n];
}

__global__ void __launch_bounds__(kSelectThreads)
    sweepSelectKernel(Img best, Img aggregated, Img costs, Img mask, SweepParams p) {
  beginKernel();
  const int lane = threadIdx.x & 31;
  const long long pixel = (long long)blockIdx.x * kSelectPixels + threadIdx.x / 32;
  if (pixel >= (long long)best.width * best.height) return;  // whole warps
  const int x = int(pixel % best.width), y = int(pixel / best.width);
  float q = -1.f, winnerCost = kNoCost;
  if (masked(mask, x, y)) {
    const float* const a = &at(aggregated, x, y);
    const float* const c = &at(costs, x, y);
    // Each lane's first minimum over its planes (ascending), then the warp's: the
    // oracle's first k minimising `aggregated` among the scored.
    int winner = -1;
    float lowest = 0.f;
    for (int k = lane; k < p.planes; k += 32)
      if (c[k] < kNoCost && (winner < 0 || a[k] < lowest)) winner = k, lowest = a[k];
    warpFirstMin(lowest, winner);
    if (winner >= 0) {
      q = refinedInverseDepth(a, c, p.planes, 0, winner, p);
      winnerCost = c[winner];
    }
  }
  if (lane != 0) return;
  at(best, x, y, 0) = q;
  at(best, x, y, 1) = winnerCost;
}

// The round-trip confidence of pixel (x, y), its ray and x_q (`there`); false
// (confidence 0) where the reference has no hypothesis or the round trip fails (the
// oracle's RoundTrip::evaluated).
__device__ bool roundTrip(const Img& best, const Img& other, const Img& mask, const SweepParams& p, float tolerancePx,
                          float maxCost, int x, int y, V3& ray, V2& there, float& confidence) {
  const float q = at(best, x, y, 0);
  if (!masked(mask, x, y) || q < 0.f || !cameraUnproject(p.cam, double(x), double(y), ray) ||
      !projectHypothesis(p.cam, ray, p.t, double(q), there))
    return false;
  // The other view's hypothesis at the nearest pixel (std::lround: halves away from zero),
  // carried back along -t.
  const int nx = int(llround(there.x)), ny = int(llround(there.y));
  if (!masked(mask, nx, ny)) return false;
  const float qOther = at(other, nx, ny, 0);
  const double back[3] = {-p.t[0], -p.t[1], -p.t[2]};
  V3 rayOther;
  V2 returned;
  if (qOther < 0.f || !cameraUnproject(p.cam, there.x, there.y, rayOther) ||
      !projectHypothesis(p.cam, rayOther, back, double(qOther), returned))
    return false;
  const double e = hypot(returned.x - x, returned.y - y) / double(tolerancePx);
  confidence = at(best, x, y, 1) > maxCost ? 0.f : float(exp(-e * e));
  return true;
}

// Pass 1: confidence everywhere; consistent pixels take the sweep's hypothesis.
__global__ void sweepInitialiseKernel(Img u, Img w, Img confidence, Img best, Img other, Img mask, SweepParams p,
                                      ConsistencyParams c) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= u.width || y >= u.height) return;
  V3 ray{0, 0, 0};
  V2 there{0, 0};
  float consistency = 0.f;
  const bool matched = roundTrip(best, other, mask, p, c.tolerancePx, c.maxCost, x, y, ray, there, consistency);
  at(confidence, x, y) = consistency;
  // Where the round trip fails or the sweep is not sure, u and w keep the coarse-to-fine
  // estimate (the oracle's test, so a NaN confidence would replace them).
  if (!matched || consistency < c.acceptConfidence) return;
  storeWarp(u, w, there, x, y);
}

// Occlusion (the oracle's occludedSurface): a pixel the other view cannot see is covered
// there by a nearer surface lying behind it along its epipolar curve (the nearer surface
// moves further and overtakes it), so the pixel belongs to the farther surface ahead of
// it. One-pixel steps along the curve's direction at the pixel, d = J t / |J t| (the
// image motion of growing inverse depth), rounded to the nearest pixel and stopping at
// the mask, find the first consistent pixel on each side within `reach`. When the one
// behind is nearer (larger q) than the one ahead: the one ahead's q; -1 otherwise.
__device__ double occludedSurface(const Img& best, const Img& confidence, const Img& mask, const SweepParams& p,
                                  float accept, const V3& ray, int x, int y, int reach) {
  V2 px;
  J23 J;
  if (!cameraProject(p.cam, ray, px, &J)) return -1.0;
  // Eigen's J * t: each row summed left to right.
  double dx = J.m[0][0] * p.t[0] + J.m[0][1] * p.t[1] + J.m[0][2] * p.t[2];
  double dy = J.m[1][0] * p.t[0] + J.m[1][1] * p.t[1] + J.m[1][2] * p.t[2];
  const double norm = sqrt(dx * dx + dy * dy);
  if (!(norm > 0.0)) return -1.0;
  dx /= norm;
  dy /= norm;
  double nearest[2] = {-1.0, -1.0};  // behind, ahead
  for (int side = 0; side < 2; ++side) {
    const double sign = side == 0 ? -1.0 : 1.0;
    for (int s = 1; s <= reach; ++s) {
      const int nx = int(llround(x + sign * s * dx)), ny = int(llround(y + sign * s * dy));
      if (!masked(mask, nx, ny)) break;
      if (at(confidence, nx, ny) < accept) continue;
      nearest[side] = at(best, nx, ny, 0);
      break;
    }
  }
  return nearest[1] >= 0.0 && nearest[0] > nearest[1] ? nearest[1] : -1.0;
}

// Pass 2, over pass 1's confidence (the launch boundary orders them): inconsistent pixels
// whose round trip could be made and that lie in front of a nearer surface take the
// surface ahead of them; the rest (no hypothesis, a match leaving the other view, or no
// occlusion) keep the coarse-to-fine estimate. Reads confidence around the pixel, writes
// u and w at the pixel only. An occluded band is at most as wide as the largest motion,
// about `planes` px, hence the reach.
__global__ void sweepOcclusionKernel(Img u, Img w, Img confidence, Img best, Img other, Img mask, SweepParams p,
                                     ConsistencyParams c) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= u.width || y >= u.height) return;
  if (at(confidence, x, y) >= c.acceptConfidence) return;
  V3 ray{0, 0, 0};
  V2 there{0, 0};
  float consistency = 0.f;
  if (!roundTrip(best, other, mask, p, c.tolerancePx, c.maxCost, x, y, ray, there, consistency)) return;
  const double q = occludedSurface(best, confidence, mask, p, c.acceptConfidence, ray, x, y, p.planes);
  if (q >= 0.0 && projectHypothesis(p.cam, ray, p.t, q, there)) storeWarp(u, w, there, x, y);
}

}  // namespace

cudaError_t launchSweepWarp(cudaStream_t s, Img volume, Img image, Img mask, const SweepParams& p) {
  const dim3 grid((volume.width + kWarpPixels - 1) / kWarpPixels, volume.height);
  CS_LAUNCH(sweepWarpKernel, grid, kWarpThreads, 0, s, volume, image, mask, p);
  return cudaGetLastError();
}

cudaError_t launchSweepCost(cudaStream_t s, Img costs, Img reference, Img volume, Img mask, const SweepParams& p) {
  const int runs = (costs.width + kCostRun - 1) / kCostRun;
  const dim3 grid(unsigned((runs * p.planes + kCostThreads - 1) / kCostThreads), unsigned(costs.height));
  switch (p.radius) {
    case 0:
      CS_LAUNCH(sweepCostKernel<0>, grid, kCostThreads, 0, s, costs, reference, volume, mask, p);
      break;
    case 1:
      CS_LAUNCH(sweepCostKernel<1>, grid, kCostThreads, 0, s, costs, reference, volume, mask, p);
      break;
    case 2:
      CS_LAUNCH(sweepCostKernel<2>, grid, kCostThreads, 0, s, costs, reference, volume, mask, p);
      break;
    case 3:
      CS_LAUNCH(sweepCostKernel<3>, grid, kCostThreads, 0, s, costs, reference, volume, mask, p);
      break;
    case 4:
      CS_LAUNCH(sweepCostKernel<4>, grid, kCostThreads, 0, s, costs, reference, volume, mask, p);
      break;
    default:
      CS_LAUNCH(sweepCostWideKernel, grid, kCostThreads, 0, s, costs, reference, volume, mask, p);
  }
  static_assert(kMaxRingRadius == 4, "one case per ring radius");
  return cudaGetLastError();
}

namespace {

// The aggregation for J chunks of 32 planes: the four directions' walks, then their sum.
template <int J>
cudaError_t launchAggregate(cudaStream_t s, Img aggregated, Img spare, Img costs, Img mask, const SweepParams& p) {
  const dim3 grid(unsigned(max(costs.width, costs.height)), 4);
  CS_LAUNCH(sweepDirectionKernel<J>, grid, dim3(32), 0, s, aggregated, spare, costs, mask, p);
  const size_t n = size_t(aggregated.width) * aggregated.height * aggregated.channels;
  const unsigned blocks = unsigned(std::min<size_t>((n + 255) / 256, 4096));
  CS_LAUNCH(sweepCombineKernel, dim3(blocks), dim3(256), 0, s, aggregated, spare);
  return cudaGetLastError();
}

}  // namespace

// Planes rounded up to a chunk count with a kernel (every count up to 6, then 8 and 16).
cudaError_t launchSweepAggregate(cudaStream_t s, Img aggregated, Img spare, Img costs, Img mask, const SweepParams& p) {
  static_assert(kMaxSweepPlanes == 16 * 32, "the largest chunk count");
  switch ((p.planes + 31) / 32) {
    case 1:
      return launchAggregate<1>(s, aggregated, spare, costs, mask, p);
    case 2:
      return launchAggregate<2>(s, aggregated, spare, costs, mask, p);
    case 3:
      return launchAggregate<3>(s, aggregated, spare, costs, mask, p);
    case 4:
      return launchAggregate<4>(s, aggregated, spare, costs, mask, p);
    case 5:
      return launchAggregate<5>(s, aggregated, spare, costs, mask, p);
    case 6:
      return launchAggregate<6>(s, aggregated, spare, costs, mask, p);
    case 7:
    case 8:
      return launchAggregate<8>(s, aggregated, spare, costs, mask, p);
    case 9:
    case 10:
    case 11:
    case 12:
    case 13:
    case 14:
    case 15:
    case 16:
      return launchAggregate<16>(s, aggregated, spare, costs, mask, p);
    default:
      return cudaErrorInvalidValue;
  }
}

cudaError_t launchSweepSelect(cudaStream_t s, Img best, Img aggregated, Img costs, Img mask, const SweepParams& p) {
  const long long pixels = (long long)best.width * best.height;
  const dim3 grid(unsigned((pixels + kSelectPixels - 1) / kSelectPixels));
  CS_LAUNCH(sweepSelectKernel, grid, kSelectThreads, 0, s, best, aggregated, costs, mask, p);
  return cudaGetLastError();
}

// Two launches: the occlusion pass reads the confidence of pixels around its own, which
// the first pass must have written everywhere.
cudaError_t launchSweepInitialise(cudaStream_t s, Img u, Img w, Img confidence, Img best, Img other, Img mask,
                                  const SweepParams& p, const ConsistencyParams& c) {
  const dim3 block(16, 8);
  CS_LAUNCH(sweepInitialiseKernel, grid2d(u.width, u.height, block), block, 0, s, u, w, confidence, best, other, mask,
            p, c);
  CS_LAUNCH(sweepOcclusionKernel, grid2d(u.width, u.height, block), block, 0, s, u, w, confidence, best, other, mask, p,
            c);
  return cudaGetLastError();
}

}  // namespace cs::cudak

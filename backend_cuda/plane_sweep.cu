// Plane-sweep initialisation (cpu/plane_sweep.cpp): spheres of constant inverse depth
// around the reference camera, swept through the camera model, scored by ZNCC, aggregated
// semi-globally, chosen winner-take-all and checked left against right. Geometry in double
// through the device camera models, intensities and costs in float, every sum in the
// oracle's order (the kernels are built with --fmad=false, so floats match bit for bit).
#include <algorithm>

#include "camera_models.cuh"

namespace cs::cudak {

namespace {

constexpr float kNoSample = -1.f;  // volume value where the hypothesis cannot be sampled
constexpr float kNoCost = 2.f;     // cost where nothing scored (the worst 1 - ZNCC)

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
// 0.28 for a thread per (pixel, plane) summing its whole window.
constexpr int kCostThreads = 128;
constexpr int kCostRun = 32;
constexpr int kMaxRingRadius = 4;  // radii with a register ring; wider windows sum afresh

// sweepAggregate: one block per scanline, one thread per plane (planes rounded up to a
// warp, at most kMaxSweepPlanes); the line is walked step by step with one barrier a step.
// A cost above 1 (anticorrelated windows) says no more than "no match": capped (oracle's kCostCap).
constexpr float kCostCap = 1.f;

// sweepSelect: one warp per pixel, lanes over the planes, so the reads of a pixel's
// planes coalesce.
constexpr int kSelectThreads = 256;
constexpr int kSelectPixels = kSelectThreads / 32;
constexpr float kPaths = 4.f;  // the aggregation's directions

// std::min(a, b) exactly (b < a ? b : a), including which operand a NaN leaves.
__device__ __forceinline__ float stdMin(float a, float b) { return b < a ? b : a; }

__device__ __forceinline__ double planeInverseDepth(const SweepDev& p, double k) {
  return p.qMax * k / double(p.planes - 1);
}

// Where the reference ray, on the sphere of inverse depth q, lands in the other view
// (BuiltCamera::project && inImage).
__device__ __forceinline__ bool projectHypothesis(const CamDev& cam, const V3& ray, const double t[3], double q,
                                                  V2& px) {
  const V3 moved{ray.x + q * t[0], ray.y + q * t[1], ray.z + q * t[2]};
  return cameraProject(cam, moved, px) && px.x >= -0.5 && px.y >= -0.5 && px.x <= cam.width - 0.5 &&
         px.y <= cam.height - 0.5;
}

__global__ void __launch_bounds__(kWarpThreads) sweepWarpKernel(Img volume, Img image, Img mask, SweepDev p) {
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

// Vertex of the parabola through (-1, before), (0, best), (1, after), within half a plane.
__device__ float parabolaOffset(float before, float best, float after) {
  if (before >= kNoCost || after >= kNoCost) return 0.f;
  const float curvature = before - 2.f * best + after;
  if (!(curvature > 1e-6f)) return 0.f;
  const float v = 0.5f * (before - after) / curvature;
  const float low = -0.5f < v ? v : -0.5f;  // std::max(-0.5f, v)
  return low < 0.5f ? low : 0.5f;           // std::min(0.5f, low)
}

// 1 - ZNCC of one window from its sums (the oracle's windowCost after the sums).
struct WindowSums {
  float n, s0, s1, s00, s11, s01;
};

__device__ __forceinline__ void addColumn(WindowSums& s, const WindowSums& c) {
  s.n += c.n, s.s0 += c.s0, s.s1 += c.s1, s.s00 += c.s00, s.s11 += c.s11, s.s01 += c.s01;
}

__device__ __forceinline__ float windowCost(const WindowSums& s, int side, float flatVariance) {
  if (2.f * s.n < float(side * side)) return kNoCost;
  const float m0 = s.s0 / s.n, m1 = s.s1 / s.n;
  const float d0 = s.s00 / s.n - m0 * m0, d1 = s.s11 / s.n - m1 * m1;
  const float v0 = 0.f < d0 ? d0 : 0.f, v1 = 0.f < d1 ? d1 : 0.f;  // std::max(0.f, d)
  const float cov = s.s01 / s.n - m0 * m1;
  return 1.f - cov / sqrtf((v0 + flatVariance) * (v1 + flatVariance));
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
    s.n += valid ? 1.f : 0.f;
    s.s0 += valid ? a : 0.f;
    s.s1 += valid ? b : 0.f;
    s.s00 += valid ? a * a : 0.f;
    s.s11 += valid ? b * b : 0.f;
    s.s01 += valid ? a * b : 0.f;
  }
  return s;
}

// The thread's plane k and run of pixels [x0, x1) of row blockIdx.y; false past the row.
__device__ __forceinline__ bool costWork(const Img& costs, int planes, CostSource& src, int& x0, int& x1,
                                         float*& out) {
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
    sweepCostKernel(Img costs, Img reference, Img volume, Img mask, SweepDev p) {
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
    sweepCostWideKernel(Img costs, Img reference, Img volume, Img mask, SweepDev p) {
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

// The scanline a block walks: the pixel index of its first pixel and the index step
// between neighbours along it.
struct Line {
  size_t start, stride;
  int length;
};

struct AggregateShared {
  float previous[2][kMaxSweepPlanes];  // the last two steps' L_r, alternating: neighbours' values
  float warpMin[2][kMaxSweepPlanes / 32];
};

// What a step reads, loaded one step ahead (unconditionally, so the loads do not wait for
// the mask) to overlap the previous step's barrier.
struct AggregateInput {
  bool inside;
  float cost;
};

__device__ AggregateInput loadStep(const Img& costs, const Img& mask, size_t pixel, int k) {
  return {__ldg(&mask.data[pixel * mask.channels]) != 0.f, __ldg(&costs.data[pixel * costs.channels + k])};
}

// The minimum of v over the block; every thread gets it. One barrier, and the per-warp
// minima alternate between two buffers so the next call cannot overwrite them early.
__device__ float blockMin(float v, float (&warpMin)[kMaxSweepPlanes / 32]) {
  for (int offset = 16; offset > 0; offset /= 2) v = fminf(v, __shfl_xor_sync(0xffffffffu, v, offset));
  if ((threadIdx.x & 31) == 0) warpMin[threadIdx.x / 32] = v;
  __syncthreads();
  float m = warpMin[0];
  for (int w = 1; w < int(blockDim.x / 32); ++w) m = fminf(m, warpMin[w]);
  return m;
}

// One direction along the block's line (the oracle's aggregateDirection for one line):
// thread k keeps L_r(., k) in a register and publishes it in shared memory for planes
// k -+ 1; the previous step's minimum m comes from blockMin. `out` receives 0 + L (the
// oracle's aggregated += l from a cleared buffer) and 0 outside the mask.
__device__ void aggregatePass(const Img& out, const Img& costs, const Img& mask, const SweepDev& p, const Line& line,
                              bool forward, AggregateShared& s) {
  int buffer = 0;
  const int k = threadIdx.x;
  const bool plane = k < p.planes;
  const int kLoad = plane ? k : p.planes - 1;  // spare threads load a valid address
  auto pixelAt = [&](int step) { return line.start + size_t(forward ? step : line.length - 1 - step) * line.stride; };
  bool havePrevious = false;
  float own = 0.f, previousMin = 0.f;
  AggregateInput next = loadStep(costs, mask, pixelAt(0), kLoad);
  for (int step = 0; step < line.length; ++step) {
    const size_t pixel = pixelAt(step);
    const AggregateInput in = next;
    if (step + 1 < line.length) next = loadStep(costs, mask, pixelAt(step + 1), kLoad);
    float& written = out.data[pixel * out.channels + kLoad];
    if (!in.inside) {  // the same for the whole block: no barrier is skipped by some threads only
      if (plane) written = 0.f;
      havePrevious = false;
      continue;
    }
    float l = kNoCost;
    if (plane) {
      const float c = stdMin(in.cost, kCostCap);
      l = c;
      if (havePrevious) {
        const float* previous = s.previous[buffer ^ 1];
        float v = stdMin(own, previousMin + p.p2);
        if (k > 0) v = stdMin(v, previous[k - 1] + p.p1);
        if (k + 1 < p.planes) v = stdMin(v, previous[k + 1] + p.p1);
        l = c + v - previousMin;
      }
      s.previous[buffer][k] = l;
      written = 0.f + l;
    }
    own = l;
    previousMin = blockMin(plane ? l : INFINITY, s.warpMin[buffer]);  // its barrier also publishes `previous`
    havePrevious = true;
    buffer ^= 1;
  }
}

// One direction of one line per block, the four directions at once (blockIdx.y: +x, -x,
// +y, -y), each into its own buffer: `aggregated` for +x, slices of `spare` for the rest.
// A walk is a chain of dependent steps bound by memory latency; four side by side keep
// the GPU four times as busy as two walks after two. sweepCombineKernel then adds them in
// the oracle's order.
__device__ Img directionBuffer(const Img& aggregated, const Img& spare, int direction) {
  if (direction == 0) return aggregated;
  const size_t size = size_t(aggregated.width) * aggregated.height * aggregated.channels;
  return Img{spare.data + size * size_t(direction - 1), aggregated.width, aggregated.height, aggregated.channels};
}

__global__ void __launch_bounds__(kMaxSweepPlanes)
    sweepDirectionKernel(Img aggregated, Img spare, Img costs, Img mask, SweepDev p) {
  beginKernel();
  __shared__ AggregateShared s;
  const int direction = blockIdx.y, width = costs.width;
  const bool rows = direction < 2;
  if (int(blockIdx.x) >= (rows ? costs.height : width)) return;  // the whole block
  const Line line = rows ? Line{size_t(blockIdx.x) * width, 1, width} : Line{blockIdx.x, size_t(width), costs.height};
  aggregatePass(directionBuffer(aggregated, spare, direction), costs, mask, p, line, direction % 2 == 0, s);
}

// aggregated = ((L+x + L-x) + L+y) + L-y, the oracle's sum (0 outside the mask, where
// every direction wrote 0).
__global__ void sweepCombineKernel(Img aggregated, Img spare) {
  beginKernel();
  const size_t n = size_t(aggregated.width) * aggregated.height * aggregated.channels;
  for (size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x; i < n; i += size_t(gridDim.x) * blockDim.x)
    aggregated.data[i] = ((aggregated.data[i] + spare.data[i]) + spare.data[i + n]) + spare.data[i + 2 * n];
}

// The first minimum of (value, k) over a warp; k = -1 (nothing scored) loses to everything.
__device__ void warpFirstMin(float& value, int& k) {
  for (int offset = 16; offset > 0; offset /= 2) {
    const float otherValue = __shfl_xor_sync(0xffffffffu, value, offset);
    const int otherK = __shfl_xor_sync(0xffffffffu, k, offset);
    if (otherK >= 0 && (k < 0 || otherValue < value || (otherValue == value && otherK < k)))
      value = otherValue, k = otherK;
  }
}

__global__ void __launch_bounds__(kSelectThreads)
    sweepSelectKernel(Img best, Img aggregated, Img costs, Img mask, SweepDev p) {
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
      // The parabola sees the aggregated cost per path, on the scale of one window's cost.
      auto score = [&](int k) { return k < 0 || k >= p.planes || c[k] >= kNoCost ? kNoCost : a[k] / kPaths; };
      // float, as the oracle's int + float
      const float k = float(winner) + parabolaOffset(score(winner - 1), score(winner), score(winner + 1));
      const double depth = planeInverseDepth(p, double(k));
      q = float(0.0 < depth ? depth : 0.0);  // std::max(0.0, depth)
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
__device__ bool roundTrip(const Img& best, const Img& other, const Img& mask, const SweepDev& p, float tolerancePx,
                          int x, int y, V3& ray, V2& there, float& confidence) {
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
  confidence = float(exp(-e * e));
  return true;
}

// The warp (u, w) of pixel (x, y) whose hypothesis lands at `there` (the oracle's setWarp).
__device__ void storeWarp(const Img& u, const Img& w, const V2& there, int x, int y) {
  const double wx = there.x - x, wy = there.y - y;
  at(w, x, y, 0) = float(wx);
  at(w, x, y, 1) = float(wy);
  at(u, x, y) = float(sqrt(wx * wx + wy * wy));
}

// Pass 1: confidence everywhere; consistent pixels take the sweep's hypothesis.
__global__ void sweepInitialiseKernel(Img u, Img w, Img confidence, Img best, Img other, Img mask, SweepDev p,
                                      ConsistencyDev c) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= u.width || y >= u.height) return;
  V3 ray{0, 0, 0};
  V2 there{0, 0};
  float consistency = 0.f;
  const bool matched = roundTrip(best, other, mask, p, c.tolerancePx, x, y, ray, there, consistency);
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
__device__ double occludedSurface(const Img& best, const Img& confidence, const Img& mask, const SweepDev& p,
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
__global__ void sweepOcclusionKernel(Img u, Img w, Img confidence, Img best, Img other, Img mask, SweepDev p,
                                     ConsistencyDev c) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= u.width || y >= u.height) return;
  if (at(confidence, x, y) >= c.acceptConfidence) return;
  V3 ray{0, 0, 0};
  V2 there{0, 0};
  float consistency = 0.f;
  if (!roundTrip(best, other, mask, p, c.tolerancePx, x, y, ray, there, consistency)) return;
  const double q = occludedSurface(best, confidence, mask, p, c.acceptConfidence, ray, x, y, p.planes);
  if (q >= 0.0 && projectHypothesis(p.cam, ray, p.t, q, there)) storeWarp(u, w, there, x, y);
}

}  // namespace

cudaError_t launchSweepWarp(cudaStream_t s, Img volume, Img image, Img mask, const SweepDev& p) {
  const dim3 grid((volume.width + kWarpPixels - 1) / kWarpPixels, volume.height);
  CS_LAUNCH(sweepWarpKernel, grid, kWarpThreads, 0, s, volume, image, mask, p);
  return cudaGetLastError();
}

cudaError_t launchSweepCost(cudaStream_t s, Img costs, Img reference, Img volume, Img mask, const SweepDev& p) {
  const int runs = (costs.width + kCostRun - 1) / kCostRun;
  const dim3 grid(unsigned((runs * p.planes + kCostThreads - 1) / kCostThreads), unsigned(costs.height));
  switch (p.radius) {
    case 0: CS_LAUNCH(sweepCostKernel<0>, grid, kCostThreads, 0, s, costs, reference, volume, mask, p); break;
    case 1: CS_LAUNCH(sweepCostKernel<1>, grid, kCostThreads, 0, s, costs, reference, volume, mask, p); break;
    case 2: CS_LAUNCH(sweepCostKernel<2>, grid, kCostThreads, 0, s, costs, reference, volume, mask, p); break;
    case 3: CS_LAUNCH(sweepCostKernel<3>, grid, kCostThreads, 0, s, costs, reference, volume, mask, p); break;
    case 4: CS_LAUNCH(sweepCostKernel<4>, grid, kCostThreads, 0, s, costs, reference, volume, mask, p); break;
    default: CS_LAUNCH(sweepCostWideKernel, grid, kCostThreads, 0, s, costs, reference, volume, mask, p);
  }
  static_assert(kMaxRingRadius == 4, "one case per ring radius");
  return cudaGetLastError();
}

// Two launches: the four directions side by side, then their sum.
cudaError_t launchSweepAggregate(cudaStream_t s, Img aggregated, Img spare, Img costs, Img mask, const SweepDev& p) {
  if (p.planes > kMaxSweepPlanes) return cudaErrorInvalidValue;
  const int threads = (p.planes + 31) / 32 * 32;
  const dim3 grid(unsigned(max(costs.width, costs.height)), 4);
  CS_LAUNCH(sweepDirectionKernel, grid, dim3(threads), 0, s, aggregated, spare, costs, mask, p);
  const size_t n = size_t(aggregated.width) * aggregated.height * aggregated.channels;
  const unsigned blocks = unsigned(std::min<size_t>((n + 255) / 256, 4096));
  CS_LAUNCH(sweepCombineKernel, dim3(blocks), dim3(256), 0, s, aggregated, spare);
  return cudaGetLastError();
}

cudaError_t launchSweepSelect(cudaStream_t s, Img best, Img aggregated, Img costs, Img mask, const SweepDev& p) {
  const long long pixels = (long long)best.width * best.height;
  const dim3 grid(unsigned((pixels + kSelectPixels - 1) / kSelectPixels));
  CS_LAUNCH(sweepSelectKernel, grid, kSelectThreads, 0, s, best, aggregated, costs, mask, p);
  return cudaGetLastError();
}

// Two launches: the occlusion pass reads the confidence of pixels around its own, which
// the first pass must have written everywhere.
cudaError_t launchSweepInitialise(cudaStream_t s, Img u, Img w, Img confidence, Img best, Img other, Img mask,
                                  const SweepDev& p, const ConsistencyDev& c) {
  const dim3 block(16, 8);
  CS_LAUNCH(sweepInitialiseKernel, grid2d(u.width, u.height, block), block, 0, s, u, w, confidence, best, other, mask,
            p, c);
  CS_LAUNCH(sweepOcclusionKernel, grid2d(u.width, u.height, block), block, 0, s, u, w, confidence, best, other, mask, p,
            c);
  return cudaGetLastError();
}

}  // namespace cs::cudak

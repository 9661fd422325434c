// Plane-sweep initialisation (cpu/plane_sweep.cpp): spheres of constant inverse depth
// around the reference camera, swept through the camera model, scored by ZNCC, chosen
// winner-take-all and checked left against right. Geometry in double through the device
// camera models, intensities and costs in float, every sum in the oracle's order.
#include "camera_models.cuh"

namespace cs::cudak {

namespace {

constexpr float kNoSample = -1.f;  // volume value where the hypothesis cannot be sampled
constexpr float kNoCost = 2.f;     // cost where nothing scored (the worst 1 - ZNCC)
constexpr float kFlatVariance = 1e-5f;

// sweepWarp: pixels of one row per block. Their rays are unprojected once (the iterative
// inverse models are the expensive part) and the block's threads then walk the
// (pixel, plane) pairs plane-fastest, which is the volume's memory order: writes coalesce.
constexpr int kWarpPixels = 32;
constexpr int kWarpThreads = 256;

// sweepSelect: a tile of pixels per block, one thread per pixel. The reference and mask
// windows are staged once; the volume is staged kChunk planes at a time (kChunk adjacent
// floats per pixel: one 32-byte sector), so every window sample is read from global
// memory once per tile instead of (2r+1)^2 times.
constexpr int kTileX = 32;  // one warp per tile row: shared-memory reads are conflict-free
constexpr int kTileY = 8;
constexpr int kChunk = 8;

__device__ __forceinline__ double planeInverseDepth(const SweepDev& p, double k) {
  return p.qMax * k / double(p.planes - 1);
}

// Where the reference ray, on the sphere of inverse depth q, lands in the other view
// (Camera::project && Camera::inImage).
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

// The staged tile with its halo of `radius` pixels on every side.
struct Tile {
  int x0, y0;          // image coordinates of the halo's top-left sample
  int width, height;   // halo size
  float* reference;    // [width * height]
  float* volume;       // [kChunk][width * height]; kNoSample where the mask is 0 or outside
  unsigned char* use;  // [width * height]: masked(mask, x, y)
  __device__ int size() const { return width * height; }
};

__device__ void stageReference(const Tile& t, const Img& reference, const Img& mask) {
  for (int i = threadIdx.y * blockDim.x + threadIdx.x; i < t.size(); i += blockDim.x * blockDim.y) {
    const int x = t.x0 + i % t.width, y = t.y0 + i / t.width;
    const bool m = masked(mask, x, y);
    t.use[i] = m;
    t.reference[i] = m ? __ldg(&at(reference, x, y)) : 0.f;
  }
}

// Planes k0 .. k0 + kChunk - 1 (those below `planes`); consecutive threads read
// consecutive planes of one pixel. Folding the mask in as kNoSample leaves the window
// loop a single test, with the oracle's outcome (unmasked and unsampled both skip).
__device__ void stageVolume(const Tile& t, const Img& volume, int k0, int planes) {
  for (int i = threadIdx.y * blockDim.x + threadIdx.x; i < t.size() * kChunk; i += blockDim.x * blockDim.y) {
    const int pixel = i / kChunk, c = i % kChunk;
    if (k0 + c >= planes) continue;
    const int x = t.x0 + pixel % t.width, y = t.y0 + pixel / t.width;
    t.volume[c * t.size() + pixel] = t.use[pixel] ? __ldg(&at(volume, x, y, k0 + c)) : kNoSample;
  }
}

// 1 - ZNCC of the window around tile pixel (tx, ty) at chunk plane c: the oracle's
// windowCost, same sums in the same order (dy outer, dx inner).
__device__ float windowCost(const Tile& t, int tx, int ty, int c, int radius) {
  const float* volume = t.volume + c * t.size();
  float n = 0, s0 = 0, s1 = 0, s00 = 0, s11 = 0, s01 = 0;
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx) {
      const int i = (ty + radius + dy) * t.width + tx + radius + dx;
      const float b = volume[i];
      if (b < 0.f) continue;
      const float a = t.reference[i];
      n += 1.f, s0 += a, s1 += b, s00 += a * a, s11 += b * b, s01 += a * b;
    }
  const int side = 2 * radius + 1;
  if (2.f * n < float(side * side)) return kNoCost;
  const float m0 = s0 / n, m1 = s1 / n;
  const float d0 = s00 / n - m0 * m0, d1 = s11 / n - m1 * m1;
  const float v0 = 0.f < d0 ? d0 : 0.f, v1 = 0.f < d1 ? d1 : 0.f;  // std::max(0.f, d)
  const float cov = s01 / n - m0 * m1;
  return 1.f - cov / sqrtf((v0 + kFlatVariance) * (v1 + kFlatVariance));
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

// The running winner-take-all of one pixel over the planes in order: the first minimum,
// with the costs of the planes either side of it for the parabola.
struct Winner {
  int k = -1;
  float cost = kNoCost, before = kNoCost, after = kNoCost, previous = kNoCost;
  __device__ void add(int plane, float c) {
    if (c < cost) {
      k = plane, cost = c, before = previous, after = kNoCost;
    } else if (plane == k + 1) {
      after = c;
    }
    previous = c;
  }
};

__global__ void __launch_bounds__(kTileX* kTileY)
    sweepSelectKernel(Img best, Img reference, Img volume, Img mask, SweepDev p) {
  beginKernel();
  extern __shared__ float shared[];
  const int r = p.radius;
  Tile t;
  t.x0 = blockIdx.x * kTileX - r, t.y0 = blockIdx.y * kTileY - r;
  t.width = kTileX + 2 * r, t.height = kTileY + 2 * r;
  t.reference = shared;
  t.volume = shared + t.size();
  t.use = reinterpret_cast<unsigned char*>(shared + (1 + kChunk) * t.size());

  const int x = blockIdx.x * kTileX + threadIdx.x, y = blockIdx.y * kTileY + threadIdx.y;
  // Threads outside the image or the mask still stage their share of the tile.
  const bool active = x < best.width && y < best.height && masked(mask, x, y);
  stageReference(t, reference, mask);
  Winner w;
  for (int k0 = 0; k0 < p.planes; k0 += kChunk) {
    __syncthreads();  // the previous chunk is no longer read (and `use` is staged)
    stageVolume(t, volume, k0, p.planes);
    __syncthreads();
    if (!active) continue;
    const int chunk = min(kChunk, p.planes - k0);
    for (int c = 0; c < chunk; ++c) w.add(k0 + c, windowCost(t, threadIdx.x, threadIdx.y, c, r));
  }
  if (x >= best.width || y >= best.height) return;
  float q = -1.f, cost = kNoCost;
  if (active && w.k >= 0) {
    const float k = float(w.k) + parabolaOffset(w.before, w.cost, w.after);  // float, as the oracle's int + float
    const double depth = planeInverseDepth(p, double(k));
    q = float(0.0 < depth ? depth : 0.0);  // std::max(0.0, depth)
    cost = w.cost;
  }
  at(best, x, y, 0) = q;
  at(best, x, y, 1) = cost;
}

// The round-trip confidence of pixel (x, y) and x_q (`there`); false (confidence 0) where
// the reference has no hypothesis or the round trip fails.
__device__ bool roundTrip(const Img& best, const Img& other, const Img& mask, const SweepDev& p, float tolerancePx,
                          int x, int y, V2& there, float& confidence) {
  const float q = at(best, x, y, 0);
  V3 ray;
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

__global__ void sweepInitialiseKernel(Img u, Img w, Img confidence, Img best, Img other, Img mask, SweepDev p,
                                      ConsistencyDev c) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= u.width || y >= u.height) return;
  V2 there{0, 0};
  float consistency = 0.f;
  const bool matched = roundTrip(best, other, mask, p, c.tolerancePx, x, y, there, consistency);
  at(confidence, x, y) = consistency;
  // Where the round trip fails or the sweep is not sure, u and w keep the coarse-to-fine
  // estimate (the oracle's test, so a NaN confidence would replace them).
  if (!matched || consistency < c.acceptConfidence) return;
  const double wx = there.x - x, wy = there.y - y;
  at(w, x, y, 0) = float(wx);
  at(w, x, y, 1) = float(wy);
  at(u, x, y) = float(sqrt(wx * wx + wy * wy));
}

}  // namespace

cudaError_t launchSweepWarp(cudaStream_t s, Img volume, Img image, Img mask, const SweepDev& p) {
  const dim3 grid((volume.width + kWarpPixels - 1) / kWarpPixels, volume.height);
  CS_LAUNCH(sweepWarpKernel, grid, kWarpThreads, 0, s, volume, image, mask, p);
  return cudaGetLastError();
}

cudaError_t launchSweepSelect(cudaStream_t s, Img best, Img reference, Img volume, Img mask, const SweepDev& p) {
  const int halo = (kTileX + 2 * p.radius) * (kTileY + 2 * p.radius);
  const size_t bytes = size_t(halo) * (1 + kChunk) * sizeof(float) + size_t(halo);
  if (bytes > 48 * 1024) {  // large windows: opt in to more than the default dynamic shared memory
    const cudaError_t e =
        cudaFuncSetAttribute(sweepSelectKernel, cudaFuncAttributeMaxDynamicSharedMemorySize, int(bytes));
    if (e != cudaSuccess) return e;
  }
  const dim3 block(kTileX, kTileY);
  CS_LAUNCH(sweepSelectKernel, grid2d(best.width, best.height, block), block, bytes, s, best, reference, volume, mask, p);
  return cudaGetLastError();
}

cudaError_t launchSweepInitialise(cudaStream_t s, Img u, Img w, Img confidence, Img best, Img other, Img mask,
                                  const SweepDev& p, const ConsistencyDev& c) {
  const dim3 block(16, 8);
  CS_LAUNCH(sweepInitialiseKernel, grid2d(u.width, u.height, block), block, 0, s, u, w, confidence, best, other, mask, p, c);
  return cudaGetLastError();
}

}  // namespace cs::cudak

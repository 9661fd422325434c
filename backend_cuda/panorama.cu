// A rig's panorama (cpu/panorama.cpp, backend.hpp panoramaPlace, panoramaSplat,
// panoramaResolve): each camera pixel placed as a footprint in the equirectangular
// panorama, splatted in three passes with atomics, then resolved. The oracle's float
// arithmetic in its order (no fused multiply-adds); atan2f and cosf are CUDA's, within a
// few ulp of the host's, so the placement agrees to rounding.
#include "common.cuh"

namespace cs::cudak {

namespace {

constexpr float kPi = 3.14159265358979323846f;

// std::max and std::clamp as the oracle calls them (the first argument where the
// comparison is false, NaN included), not fmaxf / fminf.
__device__ __forceinline__ float stdMax(float a, float b) { return a < b ? b : a; }
__device__ __forceinline__ float stdClamp(float v, float lo, float hi) { return v < lo ? lo : (hi < v ? hi : v); }

// Two inverse ranges on one surface: within a share of the larger or the solves' parallax
// noise (the oracle's sum, unfused).
__device__ __forceinline__ bool sameSurface(float inverseA, float inverseB, const PanoramaParams& p) {
  return fabsf(inverseA - inverseB) <= kPanoramaAgreement * stdMax(inverseA, inverseB) + p.parallaxSlack;
}

struct Placed {
  float column, row, range;
};

// Pixel (x, y)'s column and row in the panorama and its range from the centre; false where
// it has no estimate or no ray. Every thread places its neighbours itself: recomputing four
// placements is cheaper than a pass and a buffer to share them.
__device__ bool placePixel(const Img& radial, const Img& rays, int x, int y, const PanoramaParams& p, Placed& out) {
  const float r = at(radial, x, y);
  const float dx = at(rays, x, y, 0), dy = at(rays, x, y, 1), dz = at(rays, x, y, 2);
  if (isnan(r) || !isfinite(dx) || !isfinite(dy) || !isfinite(dz)) return false;
  const bool finite = isfinite(r);  // a point at infinity is its direction
  const float px = finite ? r * dx + p.centre[0] : dx, py = finite ? r * dy + p.centre[1] : dy,
              pz = finite ? r * dz + p.centre[2] : dz;
  const float lon = atan2f(px, pz), lat = atan2f(-py, sqrtf(px * px + pz * pz));
  const float width = float(p.width), height = float(p.width / 2);
  out.column = (lon + kPi) / (2.f * kPi) * width - 0.5f;
  out.row = (kPi / 2.f - lat) / kPi * height - 0.5f;
  out.range = finite ? sqrtf(px * px + py * py + pz * pz) : __int_as_float(0x7f800000);
  return true;
}

// The footprint's half-sizes (cpu/panorama.cpp footprint): half the largest steps to the
// neighbours on the same surface along the camera's rows (a) plus along its columns (b), at
// least half a pixel, at most kPanoramaMaxSplat of arc (a column's arc shrinks with cos of
// the latitude).
__device__ void footprint(const Img& radial, const Img& rays, int x, int y, const Placed& own, const PanoramaParams& p,
                          float& hx, float& hy) {
  const float width = float(p.width), height = float(p.width / 2), inverse = 1.f / at(radial, x, y);
  float a[2] = {0.f, 0.f}, b[2] = {0.f, 0.f};
  const int nx[4] = {x + 1, x, x - 1, x}, ny[4] = {y, y + 1, y, y - 1};
  for (int k = 0; k < 4; ++k) {
    if (!inside(radial, nx[k], ny[k])) continue;
    const float rn = at(radial, nx[k], ny[k]);
    Placed n;
    if (isnan(rn) || !sameSurface(1.f / rn, inverse, p) || !placePixel(radial, rays, nx[k], ny[k], p, n)) continue;
    float step[2] = {n.column - own.column, n.row - own.row};
    if (fabsf(step[0]) > 0.5f * width) step[0] = remainderf(step[0], width);  // across the seam
    float* along = ny[k] == y ? a : b;
    for (int i = 0; i < 2; ++i) along[i] = stdMax(along[i], fabsf(step[i]));
  }
  const float latitude = kPi / 2.f - kPi * (own.row + 0.5f) / height;
  const float columns = kPanoramaMaxSplat / stdMax(cosf(latitude), 2.f * kPanoramaMaxSplat / width);
  hx = stdClamp(0.5f * (a[0] + b[0]), 0.5f, stdMax(0.5f, columns));
  hy = stdClamp(0.5f * (a[1] + b[1]), 0.5f, kPanoramaMaxSplat);
}

// One thread per camera pixel.
__global__ void panoramaPlaceKernel(Img place, Img radial, Img rays, PanoramaParams p) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= radial.width || y >= radial.height) return;
  const float nan = __int_as_float(0x7fc00000);  // the oracle's quiet NaN, bit for bit
  float values[kPanoramaPlaceChannels] = {nan, nan, nan, nan, nan};
  Placed own;
  if (placePixel(radial, rays, x, y, p, own)) {
    float hx, hy;
    footprint(radial, rays, x, y, own, p, hx, hy);
    values[0] = own.column, values[1] = own.row, values[2] = hx, values[3] = hy, values[4] = own.range;
  }
  for (int c = 0; c < kPanoramaPlaceChannels; ++c) at(place, x, y, c) = values[c];
}

// *address = max(*address, value) for accumulators that start at 0 and only grow: the
// order of non-negative floats is that of their bits as ints, and a negative value (bits
// negative as an int) never wins over them. The plain load first skips the atomic where it
// cannot win (most splats, since neighbouring footprints overlap); a stale load is never
// above the stored value, so it only costs an atomic. A NaN value never wins, as in the
// oracle's std::max(accumulator, value).
__device__ __forceinline__ void growTo(float* address, float value) {
  if (value > *address) atomicMax(reinterpret_cast<int*>(address), __float_as_int(value));
}

// One splat's contribution to the panorama pixel at acc (6 channels), by pass. best and
// nearest are read plainly: the passes that write them finished before this launch.
__device__ void splatInto(float* acc, const PanoramaParams& p, float confidence, float weight, float inverse,
                          float grey) {
  if (p.pass == kPanoramaBest) {
    growTo(acc, confidence);
  } else if (p.pass == kPanoramaNearest) {
    if (confidence >= 0.5f * acc[0]) growTo(acc + 1, inverse);
  } else if (confidence >= 0.5f * acc[0] && sameSurface(inverse, acc[1], p)) {
    atomicAdd(acc + 2, weight * inverse);
    atomicAdd(acc + 3, weight);
    if (isfinite(grey)) atomicAdd(acc + 4, weight * grey), atomicAdd(acc + 5, weight);
  }
}

// A footprint's box: columns x0 .. x0 + columns - 1 (wrapped modulo the width when
// splatted: each column as often as the oracle's loop takes it) and rows y0 .. y0 + rows - 1
// inside the panorama; and what it adds.
struct Box {
  int x0 = 0, y0 = 0, columns = 0, rows = 0;
  float confidence = 0.f, weight = 0.f, inverse = 0.f, grey = 0.f;
  __device__ int area() const { return columns * rows; }
};

__device__ Box boxOf(Img place, Img confidence, Img grey, int cx, int cy, const PanoramaParams& p) {
  Box b;
  if (cx >= place.width || cy >= place.height) return b;
  const float column = at(place, cx, cy, 0), c0 = at(confidence, cx, cy);
  if (isnan(column) || (p.minConfidence > 0.f && !(c0 >= p.minConfidence))) return b;
  b.confidence = isfinite(c0) ? c0 : 0.f;
  b.weight = isfinite(c0) ? stdMax(c0, 1e-6f) : 1e-6f;
  const float row = at(place, cx, cy, 1), hx = at(place, cx, cy, 2), hy = at(place, cx, cy, 3);
  b.inverse = 1.f / at(place, cx, cy, 4);
  b.grey = grey.data ? at(grey, cx, cy) : __int_as_float(0x7fc00000);
  b.x0 = int(ceilf(column - hx));
  b.columns = int(floorf(column + hx)) - b.x0 + 1;
  b.y0 = max(0, int(ceilf(row - hy)));
  b.rows = max(0, min(p.width / 2 - 1, int(floorf(row + hy))) - b.y0 + 1);
  return b;
}

// Pixel k (row-major) of box b.
__device__ void splatPixel(Img accum, const Box& b, int k, const PanoramaParams& p) {
  const int x = b.x0 + k % b.columns, y = b.y0 + k / b.columns;
  splatInto(&at(accum, ((x % p.width) + p.width) % p.width, y), p, b.confidence, b.weight, b.inverse, b.grey);
}

// Boxes of at most this many pixels are their own thread's work.
constexpr int kOwnArea = 32;

// One thread per camera pixel (blocks of whole warps, no thread leaving early: the warp
// votes). A thread splats its own box when it is small; near the poles a footprint spans up
// to half the panorama's columns, and such a box is shared out over its warp's lanes, so no
// thread runs hundreds of times longer than the others beside it.
__global__ void panoramaSplatKernel(Img accum, Img place, Img confidence, Img grey, PanoramaParams p) {
  beginKernel();
  const int cx = blockIdx.x * blockDim.x + threadIdx.x, cy = blockIdx.y * blockDim.y + threadIdx.y;
  const Box own = boxOf(place, confidence, grey, cx, cy, p);
  const int area = own.area();
  if (area <= kOwnArea)
    for (int k = 0; k < area; ++k) splatPixel(accum, own, k, p);
  const int lane = int(threadIdx.x + threadIdx.y * blockDim.x) % 32;
  for (unsigned large = __ballot_sync(0xffffffffu, area > kOwnArea); large; large &= large - 1) {
    const int source = __ffs(int(large)) - 1;
    Box b;
    b.x0 = __shfl_sync(0xffffffffu, own.x0, source), b.y0 = __shfl_sync(0xffffffffu, own.y0, source);
    b.columns = __shfl_sync(0xffffffffu, own.columns, source), b.rows = __shfl_sync(0xffffffffu, own.rows, source);
    b.confidence = __shfl_sync(0xffffffffu, own.confidence, source);
    b.weight = __shfl_sync(0xffffffffu, own.weight, source);
    b.inverse = __shfl_sync(0xffffffffu, own.inverse, source);
    b.grey = __shfl_sync(0xffffffffu, own.grey, source);
    for (int k = lane; k < b.area(); k += 32) splatPixel(accum, b, k, p);
  }
}

// One thread per panorama pixel: the mean over the nearest surface, then the pixel's
// accumulator back to 0 for the next panorama.
__global__ void panoramaResolveKernel(float* range, float* grey, float* confidence, float* accum, long long n) {
  beginKernel();
  const long long i = (long long)blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  float* acc = accum + i * kPanoramaChannels;
  const float nan = __int_as_float(0x7fc00000);
  float r = nan, g = nan, c = nan;
  if (acc[3] > 0.f) {
    r = acc[3] / acc[2];  // +inf where every splat was at infinity
    c = acc[0];
    if (acc[5] > 0.f) g = acc[4] / acc[5];
  }
  range[i] = r, grey[i] = g, confidence[i] = c;
  for (int k = 0; k < kPanoramaChannels; ++k) acc[k] = 0.f;
}

}  // namespace

cudaError_t launchPanoramaPlace(cudaStream_t s, Img place, Img radial, Img rays, const PanoramaParams& p) {
  const dim3 block(16, 8);
  CS_LAUNCH(panoramaPlaceKernel, grid2d(radial.width, radial.height, block), block, 0, s, place, radial, rays, p);
  return cudaGetLastError();
}

cudaError_t launchPanoramaSplat(cudaStream_t s, Img accum, Img place, Img confidence, Img grey,
                                const PanoramaParams& p) {
  const dim3 block(16, 8);  // whole warps: the kernel votes across each
  CS_LAUNCH(panoramaSplatKernel, grid2d(place.width, place.height, block), block, 0, s, accum, place, confidence, grey,
            p);
  return cudaGetLastError();
}

cudaError_t launchPanoramaResolve(cudaStream_t s, Img range, Img grey, Img confidence, Img accum) {
  const long long n = (long long)accum.width * accum.height;
  const int block = 256;
  CS_LAUNCH(panoramaResolveKernel, unsigned((n + block - 1) / block), block, 0, s, range.data, grey.data,
            confidence.data, accum.data, n);
  return cudaGetLastError();
}

}  // namespace cs::cudak

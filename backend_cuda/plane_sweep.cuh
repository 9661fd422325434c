// Device helpers shared by the full sweep (plane_sweep.cu) and the band sweep
// (sweep_band.cu): the hypotheses' geometry, the ZNCC from a window's sums, the
// parabola refinement and the first minimum over a warp, each the oracle's arithmetic
// (cpu/plane_sweep.cpp) in its order.
#pragma once
#include "camera_models.cuh"

namespace cs::cudak {

constexpr float kNoSample = -1.f;  // volume value where the hypothesis cannot be sampled
constexpr float kNoCost = 2.f;     // cost where nothing scored (the worst 1 - ZNCC)
// A cost above 1 (anticorrelated windows) says no more than "no match": the aggregation
// caps it (oracle's kCostCap).
constexpr float kCostCap = 1.f;
constexpr float kPaths = 4.f;  // the aggregation's directions

// std::min(a, b) exactly (b < a ? b : a), including which operand a NaN leaves.
__device__ __forceinline__ float stdMin(float a, float b) { return b < a ? b : a; }

__device__ __forceinline__ double planeInverseDepth(const SweepParams& p, double k) {
  return p.qMax * k / double(p.planes - 1);
}

// Where the reference ray, on the sphere of inverse depth q, lands in the other view
// (BuiltCamera::project && inImage).
__device__ __forceinline__ bool projectHypothesis(const CameraParams& cam, const V3& ray, const double t[3], double q,
                                                  V2& px) {
  const V3 moved{ray.x + q * t[0], ray.y + q * t[1], ray.z + q * t[2]};
  return cameraProject(cam, moved, px) && px.x >= -0.5 && px.y >= -0.5 && px.x <= cam.width - 0.5 &&
         px.y <= cam.height - 0.5;
}

// Vertex of the parabola through (-1, before), (0, best), (1, after), within half a plane.
__device__ __forceinline__ float parabolaOffset(float before, float best, float after) {
  if (before >= kNoCost || after >= kNoCost) return 0.f;
  const float curvature = before - 2.f * best + after;
  if (!(curvature > 1e-6f)) return 0.f;
  const float v = 0.5f * (before - after) / curvature;
  const float low = -0.5f < v ? v : -0.5f;  // std::max(-0.5f, v)
  return low < 0.5f ? low : 0.5f;           // std::min(0.5f, low)
}

// The winner's inverse depth (>= 0), refined by the parabola through aggregated / kPaths at
// its neighbours among the pixel's n channels (none beside an unscored one), channel k
// being hypothesis start + k: the oracle's select after the winner is chosen. a, c: the
// pixel's aggregated costs and window costs.
__device__ __forceinline__ float refinedInverseDepth(const float* a, const float* c, int n, int start, int winner,
                                                     const SweepParams& p) {
  auto score = [&](int k) { return k < 0 || k >= n || c[k] >= kNoCost ? kNoCost : a[k] / kPaths; };
  // float, as the oracle's int + float
  const float k = float(start + winner) + parabolaOffset(score(winner - 1), score(winner), score(winner + 1));
  const double depth = planeInverseDepth(p, double(k));
  return float(0.0 < depth ? depth : 0.0);  // std::max(0.0, depth)
}

// 1 - ZNCC of one window from its sums (the oracle's windowCost after the sums).
struct WindowSums {
  float n, s0, s1, s00, s11, s01;
};

__device__ __forceinline__ void addColumn(WindowSums& s, const WindowSums& c) {
  s.n += c.n, s.s0 += c.s0, s.s1 += c.s1, s.s00 += c.s00, s.s11 += c.s11, s.s01 += c.s01;
}

// One window sample (a reference, b the hypothesis's) into a column's sums; an invalid one
// adds +0, which leaves a sum begun at +0 bit for bit as the oracle's skipped sample does.
__device__ __forceinline__ void addSample(WindowSums& s, bool valid, float a, float b) {
  s.n += valid ? 1.f : 0.f;
  s.s0 += valid ? a : 0.f;
  s.s1 += valid ? b : 0.f;
  s.s00 += valid ? a * a : 0.f;
  s.s11 += valid ? b * b : 0.f;
  s.s01 += valid ? a * b : 0.f;
}

__device__ __forceinline__ float windowCost(const WindowSums& s, int side, float flatVariance) {
  if (2.f * s.n < float(side * side)) return kNoCost;
  const float m0 = s.s0 / s.n, m1 = s.s1 / s.n;
  const float d0 = s.s00 / s.n - m0 * m0, d1 = s.s11 / s.n - m1 * m1;
  const float v0 = 0.f < d0 ? d0 : 0.f, v1 = 0.f < d1 ? d1 : 0.f;  // std::max(0.f, d)
  const float cov = s.s01 / s.n - m0 * m1;
  return 1.f - cov / sqrtf((v0 + flatVariance) * (v1 + flatVariance));
}

// The first minimum of (value, k) over a warp; k = -1 (nothing scored) loses to everything.
__device__ __forceinline__ void warpFirstMin(float& value, int& k) {
  for (int offset = 16; offset > 0; offset /= 2) {
    const float otherValue = __shfl_xor_sync(0xffffffffu, value, offset);
    const int otherK = __shfl_xor_sync(0xffffffffu, k, offset);
    if (otherK >= 0 && (k < 0 || otherValue < value || (otherValue == value && otherK < k)))
      value = otherValue, k = otherK;
  }
}

}  // namespace cs::cudak

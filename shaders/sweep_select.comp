#version 460
#extension GL_GOOGLE_include_directive : require
// Winner-take-all over the aggregated plane-sweep costs (backend_cpu/plane_sweep.cpp
// sweepSelect): for each masked pixel, the hypothesis minimising `aggregated` among those
// whose window cost scored (< kNoCost), the first on ties, refined by a parabola through
// aggregated / 4 (the cost per path, on the scale of one window's cost) at its
// neighbours; best = (q, its window cost), (-1, kNoCost) where nothing scored or the pixel
// is not masked. The plane index becomes an inverse depth in `real`, compiled twice:
// double (-DCS_DOUBLE, the oracle's precision) and float. One invocation per pixel.
#ifdef CS_DOUBLE
#extension GL_ARB_gpu_shader_fp64 : require
#endif
#include "common.glsl"
#include "plane_sweep.glsl"

layout(push_constant) uniform PC {
  FBuf best, aggregated, costs, mask;  // best: 2 channels; aggregated, costs: `planes`
  SweepParamsRef prm;                  // qMax
  int width, height, planes;
} pc;

// The parabola's sample at plane k: kNoCost outside the planes or where k did not score.
float score(int base, int k) {
  if (k < 0 || k >= pc.planes || pc.costs.v[base + k] >= kNoCost) return kNoCost;
  return pc.aggregated.v[base + k] / kPaths;  // exact: a power of two
}

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  pc.best.v[2 * i] = -1.0;
  pc.best.v[2 * i + 1] = kNoCost;
  if (!masked(pc.mask, pc.width, pc.height, x, y)) return;

  // The first strict minimum of the aggregated costs among the planes that scored.
  const int base = idx(pc.width, pc.planes, x, y, 0);
  int winner = -1;
  float winnerAggregated = 0.0;
  for (int k = 0; k < pc.planes; ++k) {
    if (!(pc.costs.v[base + k] < kNoCost)) continue;
    const float a = pc.aggregated.v[base + k];
    if (winner < 0 || a < winnerAggregated) {
      winner = k;
      winnerAggregated = a;
    }
  }
  if (winner < 0) return;
  const float offset = parabolaOffset(score(base, winner - 1), score(base, winner), score(base, winner + 1));
  // The oracle adds the offset to the plane index in float (int + float), then turns the
  // sum into an inverse depth in double.
  precise float k = float(winner) + offset;
  const real q = planeInverseDepth(pc.prm.qMax, pc.planes, real(k));
  pc.best.v[2 * i] = float(max(real(0.0), q));
  pc.best.v[2 * i + 1] = pc.costs.v[base + winner];
}

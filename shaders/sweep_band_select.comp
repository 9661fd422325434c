#version 460
#extension GL_GOOGLE_include_directive : require
// Winner-take-all within each pixel's band (backend_cpu/plane_sweep.cpp sweepBandSelect):
// sweep_select.comp over channels k = 0 .. band - 1 (hypothesis first + k), except that a
// winner on an edge of the band that the full range continues past (k = 0 with first > 0,
// k = band - 1 with first + band < planes) gives (-1, kNoCost): the minimum lies at or
// beyond the band, so the coarse proposal missed it. Also (-1, kNoCost) where the pixel is
// not masked, has no band or nothing scored. The hypothesis becomes an inverse depth in
// `real`, compiled twice: double (-DCS_DOUBLE, the oracle's precision) and float. One
// invocation per pixel.
#ifdef CS_DOUBLE
#extension GL_ARB_gpu_shader_fp64 : require
#endif
#include "common.glsl"
#include "plane_sweep.glsl"

layout(push_constant) uniform PC {
  FBuf best, aggregated, costs, first, mask;  // best: 2 channels; aggregated, costs: `band`
  SweepParamsRef prm;                         // qMax
  int width, height, planes, band;
} pc;

// The parabola's sample at channel k: kNoCost outside the band or where k did not score.
float score(int base, int k) {
  if (k < 0 || k >= pc.band || pc.costs.v[base + k] >= kNoCost) return kNoCost;
  return pc.aggregated.v[base + k] / kPaths;  // exact: a power of two
}

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  pc.best.v[2 * i] = -1.0;
  pc.best.v[2 * i + 1] = kNoCost;
  const int start = int(pc.first.v[i]);
  if (!masked(pc.mask, pc.width, pc.height, x, y) || start < 0) return;

  // The first strict minimum of the aggregated costs among the channels that scored.
  const int base = idx(pc.width, pc.band, x, y, 0);
  int winner = -1;
  float winnerAggregated = 0.0;
  for (int k = 0; k < pc.band; ++k) {
    if (!(pc.costs.v[base + k] < kNoCost)) continue;
    const float a = pc.aggregated.v[base + k];
    if (winner < 0 || a < winnerAggregated) {
      winner = k;
      winnerAggregated = a;
    }
  }
  if (winner < 0) return;
  if ((winner == 0 && start > 0) || (winner == pc.band - 1 && start + pc.band < pc.planes)) return;
  const float offset = parabolaOffset(score(base, winner - 1), score(base, winner), score(base, winner + 1));
  // The oracle adds the offset to the hypothesis (int + float) in float, then turns the sum
  // into an inverse depth in double.
  precise float k = float(start + winner) + offset;
  const real q = planeInverseDepth(pc.prm.qMax, pc.planes, real(k));
  pc.best.v[2 * i] = float(max(real(0.0), q));
  pc.best.v[2 * i + 1] = pc.costs.v[base + winner];
}

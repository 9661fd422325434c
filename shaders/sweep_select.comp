#version 460
#extension GL_GOOGLE_include_directive : require
// Winner-take-all over the plane-sweep volume (backend_cpu/plane_sweep.cpp sweepSelect):
// for each masked pixel, the hypothesis minimising 1 - ZNCC between the reference window
// and the volume window, the first on ties, refined by a parabola through its neighbours'
// costs; best = (q, cost), (-1, 2) where nothing scored. Pure float, like the oracle's
// costs; the sums are `precise` so that no multiply-add is fused and every backend forms
// the same costs (a cost that moves by an ulp can move the winner by a plane).
#include "common.glsl"

const float kNoCost = 2.0;  // cost where nothing scored (the worst 1 - ZNCC)
// Regularises the ZNCC of nearly flat windows (about one grey level of noise on [0, 1]).
const float kFlatVariance = 1e-5;

layout(push_constant) uniform PC {
  FBuf best, reference, volume, mask;  // best: 2 channels; volume: `planes` channels
  int width, height, planes, radius;
  float qMax;
} pc;

// 1 - ZNCC over the masked window samples whose hypothesis could be sampled; kNoCost when
// fewer than half the window's samples take part. Sums in the oracle's order.
float windowCost(int x, int y, int k) {
  precise float n = 0.0, s0 = 0.0, s1 = 0.0, s00 = 0.0, s11 = 0.0, s01 = 0.0;
  for (int dy = -pc.radius; dy <= pc.radius; ++dy)
    for (int dx = -pc.radius; dx <= pc.radius; ++dx) {
      const int sx = x + dx, sy = y + dy;
      if (!masked(pc.mask, pc.width, pc.height, sx, sy)) continue;
      const float b = pc.volume.v[idx(pc.width, pc.planes, sx, sy, k)];
      if (b < 0.0) continue;  // the hypothesis could not be sampled there
      const float a = pc.reference.v[sy * pc.width + sx];
      n += 1.0;
      s0 += a;
      s1 += b;
      s00 += a * a;
      s11 += b * b;
      s01 += a * b;
    }
  const int side = 2 * pc.radius + 1;
  if (2.0 * n < float(side * side)) return kNoCost;
  precise float m0 = s0 / n, m1 = s1 / n;
  precise float v0 = max(0.0, s00 / n - m0 * m0), v1 = max(0.0, s11 / n - m1 * m1);
  precise float cov = s01 / n - m0 * m1;
  precise float cost = 1.0 - cov / sqrt((v0 + kFlatVariance) * (v1 + kFlatVariance));
  return cost;
}

// Vertex of the parabola through (-1, before), (0, winner), (1, after), within half a
// plane; 0 where a neighbour did not score or the costs do not curve upwards.
float parabolaOffset(float before, float winner, float after) {
  if (before >= kNoCost || after >= kNoCost) return 0.0;
  precise float curvature = before - 2.0 * winner + after;
  if (!(curvature > 1e-6)) return 0.0;
  precise float offset = 0.5 * (before - after) / curvature;
  return min(0.5, max(-0.5, offset));
}

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  pc.best.v[2 * i] = -1.0;
  pc.best.v[2 * i + 1] = kNoCost;
  if (!masked(pc.mask, pc.width, pc.height, x, y)) return;

  // The first strict minimum, with the costs of the planes on either side of it.
  int winner = -1;
  float winnerCost = kNoCost, before = kNoCost, after = kNoCost, previous = kNoCost;
  for (int k = 0; k < pc.planes; ++k) {
    const float cost = windowCost(x, y, k);
    if (cost < winnerCost) {
      winner = k;
      winnerCost = cost;
      before = previous;
      after = kNoCost;
    } else if (k == winner + 1) {
      after = cost;
    }
    previous = cost;
  }
  if (winner < 0) return;
  precise float k = float(winner) + parabolaOffset(before, winnerCost, after);
  precise float q = pc.qMax * k / float(pc.planes - 1);
  pc.best.v[2 * i] = max(0.0, q);
  pc.best.v[2 * i + 1] = winnerCost;
}

#version 460
#extension GL_GOOGLE_include_directive : require
// The plane-sweep cost volume (backend_cpu/plane_sweep.cpp sweepCost): for each masked
// pixel and every hypothesis k, 1 - ZNCC between the reference window and the volume
// window; kNoCost where fewer than half the window scored and outside the mask. Pure
// float, like the oracle's costs; the sums are `precise` so that no multiply-add is fused
// and every backend forms the same costs (a cost that moves by an ulp can move the winner
// by a plane).
//
// One invocation per (pixel, plane) of a row, flattened as (x * planes + k) - the layout
// of the volume and the costs - so that neighbouring invocations read neighbouring
// floats of the volume and write neighbouring costs (coalesced), whatever `planes` is.
// Work groups: (ceil(width * planes / 256), height).
#include "common.glsl"

const float kNoCost = 2.0;  // cost where nothing scored (the worst 1 - ZNCC)

layout(push_constant) uniform PC {
  FBuf costs, reference, volume, mask;  // costs, volume: `planes` channels
  int width, height, planes, radius;
  float flatVariance;  // SweepParams::flatVariance
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
  precise float cost = 1.0 - cov / sqrt((v0 + pc.flatVariance) * (v1 + pc.flatVariance));
  return cost;
}

void main() {
  // gl_LocalInvocationIndex: the 16 x 16 work group of common.glsl as 256 in a line.
  const int i = int(gl_WorkGroupID.x * 256u + gl_LocalInvocationIndex);
  const int y = int(gl_WorkGroupID.y);
  if (i >= pc.width * pc.planes || y >= pc.height) return;
  const int x = i / pc.planes, k = i - x * pc.planes;
  pc.costs.v[idx(pc.width, pc.planes, x, y, k)] =
      masked(pc.mask, pc.width, pc.height, x, y) ? windowCost(x, y, k) : kNoCost;
}

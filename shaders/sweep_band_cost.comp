#version 460
#extension GL_GOOGLE_include_directive : require
// The band sweep's costs (backend_cpu/plane_sweep.cpp sweepBandCost): sweep_cost.comp's
// 1 - ZNCC at each pixel's hypotheses h = first(x) + k, a window sample at pixel n being
// volume(n, h - first(n)) where n has a band holding h, missing otherwise; kNoCost where
// first(x) is -1 or outside the mask. Pure float, the sums `precise` and in the oracle's
// order (dx outer: each column's partials over dy, then added into the window's sums).
// The hypothesis changes with the centre pixel's band, so the columns of one output are no
// use to the next (sweep_cost.comp's walk along x): each invocation sums its window
// directly. Invocations (x * band + k) of a row: neighbouring invocations are neighbouring
// channels of one pixel, so the volume's reads and the costs' writes are coalesced.
// Work groups: (ceil(width * band / 256), height).
#define CS_OWN_WORK_GROUP
#include "common.glsl"

layout(local_size_x = 256, local_size_y = 1, local_size_z = 1) in;

const float kNoCost = 2.0;  // cost where nothing scored (the worst 1 - ZNCC)

layout(push_constant) uniform PC {
  FBuf costs, reference, volume, first, mask;  // costs, volume: `band` channels
  int width, height, band, radius;
  float flatVariance;  // SweepParams::flatVariance
} pc;

// The window cost of hypothesis h at (x, y).
float windowCost(int x, int y, int h) {
  const int r = pc.radius, side = 2 * r + 1;
  precise float n = 0.0, s0 = 0.0, s1 = 0.0, s00 = 0.0, s11 = 0.0, s01 = 0.0;
  for (int sx = x - r; sx <= x + r; ++sx) {
    precise float cn = 0.0, c0 = 0.0, c1 = 0.0, c00 = 0.0, c11 = 0.0, c01 = 0.0;
    if (sx >= 0 && sx < pc.width) {
      for (int sy = max(y - r, 0); sy <= min(y + r, pc.height - 1); ++sy) {
        const int i = sy * pc.width + sx;
        // The loads are independent (none waits for the mask's), so they overlap.
        const float inMask = pc.mask.v[i];
        const float a = pc.reference.v[i];
        const int there = int(pc.first.v[i]), j = h - there;  // h's channel there, if held
        if (inMask == 0.0 || there < 0 || j < 0 || j >= pc.band) continue;
        const float b = pc.volume.v[i * pc.band + j];
        if (b < 0.0) continue;  // not sampled there
        cn += 1.0;
        c0 += a;
        c1 += b;
        c00 += a * a;
        c11 += b * b;
        c01 += a * b;
      }
    }
    n += cn;
    s0 += c0;
    s1 += c1;
    s00 += c00;
    s11 += c11;
    s01 += c01;
  }
  if (2.0 * n < float(side * side)) return kNoCost;
  precise float m0 = s0 / n, m1 = s1 / n;
  precise float v0 = max(0.0, s00 / n - m0 * m0), v1 = max(0.0, s11 / n - m1 * m1);
  precise float cov = s01 / n - m0 * m1;
  precise float cost = 1.0 - cov / sqrt((v0 + pc.flatVariance) * (v1 + pc.flatVariance));
  return cost;
}

void main() {
  const int i = int(gl_GlobalInvocationID.x), y = int(gl_WorkGroupID.y);
  if (i >= pc.width * pc.band || y >= pc.height) return;
  const int x = i / pc.band, k = i - x * pc.band;
  const int start = int(pc.first.v[y * pc.width + x]);
  float cost = kNoCost;
  if (start >= 0 && masked(pc.mask, pc.width, pc.height, x, y)) cost = windowCost(x, y, start + k);
  pc.costs.v[idx(pc.width, pc.band, x, y, k)] = cost;
}

#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// The plane-sweep cost volume (backend_cpu/plane_sweep.cpp sweepCost): for each masked
// pixel and every hypothesis k, 1 - ZNCC between the reference window and the volume
// window; kNoCost where fewer than half the window scored and outside the mask. Pure
// float, like the oracle's costs; the sums are `precise` so that no multiply-add is fused
// and every backend forms the same costs (a cost that moves by an ulp can move the winner
// by a plane).
//
// The oracle sums a window column by column (dx outer): each column's partial sums over
// dy, then the window's sums over the columns in dx order. So an invocation takes one
// plane k of a run of pc.run consecutive pixels of a row and walks along x keeping the
// window's 2r + 1 column partials in registers: each output adds one new column (2r + 1
// samples) instead of a whole window ((2r + 1)^2).
// Invocations (run * planes + k) of a row: neighbouring invocations are neighbouring
// planes of one pixel, so the volume's reads and the costs' writes are coalesced.
// Work groups: (ceil(runs * planes / 256), height).
#define CS_OWN_WORK_GROUP
#include "common.glsl"

layout(local_size_x = 256, local_size_y = 1, local_size_z = 1) in;

const float kNoCost = 2.0;  // cost where nothing scored (the worst 1 - ZNCC)
const int kMaxRadius = 4;   // the largest radius walked with the window in registers

layout(push_constant) uniform PC {
  FBuf costs, reference, volume, mask;  // costs, volume: `planes` channels
  int width, height, planes, radius;
  float flatVariance;  // SweepParams::flatVariance
  int run;             // pixels per invocation (backend_vulkan/kernels.cpp doSweepCost)
} pc;

// One window column's partial sums: count, a, b, aa, bb, ab.
struct Column {
  float n, s0, s1, s00, s11, s01;
};

// The column at sx, rows y - r .. y + r in order, over the masked samples whose
// hypothesis could be sampled (the oracle's validity), each sum starting at 0. The three
// loads of a sample are independent (no load waits for the mask's), so they overlap.
Column column(int sx, int y, int k, int r) {
  precise float n = 0.0, s0 = 0.0, s1 = 0.0, s00 = 0.0, s11 = 0.0, s01 = 0.0;
  if (sx >= 0 && sx < pc.width) {
    for (int sy = max(y - r, 0); sy <= min(y + r, pc.height - 1); ++sy) {
      const float inMask = pc.mask.v[sy * pc.width + sx];
      const float a = pc.reference.v[sy * pc.width + sx];
      const float b = pc.volume.v[idx(pc.width, pc.planes, sx, sy, k)];
      if (inMask == 0.0 || b < 0.0) continue;  // not masked, or not sampled there
      n += 1.0;
      s0 += a;
      s1 += b;
      s00 += a * a;
      s11 += b * b;
      s01 += a * b;
    }
  }
  return Column(n, s0, s1, s00, s11, s01);
}

// The window cost from the window's sums (the oracle's arithmetic after the sums): kNoCost
// when fewer than half the window's samples scored.
float zncc(float n, float s0, float s1, float s00, float s11, float s01, int side) {
  if (2.0 * n < float(side * side)) return kNoCost;
  precise float m0 = s0 / n, m1 = s1 / n;
  precise float v0 = max(0.0, s00 / n - m0 * m0), v1 = max(0.0, s11 / n - m1 * m1);
  precise float cov = s01 / n - m0 * m1;
  precise float cost = 1.0 - cov / sqrt((v0 + pc.flatVariance) * (v1 + pc.flatVariance));
  return cost;
}

// walk##R: the run's pixels x0 .. at plane k for window radius R, one function per
// radius (a macro, GLSL having no templates) so that the window's array has its exact
// size and every loop over it a constant trip: unrolled, every index is a constant and
// the window stays in registers (win[m] = column x - R + m, shifted down one per output:
// register moves). The first 2R steps only fill the window (one column-sum site keeps
// the code small).
#define WALK(R)                                                                         \
  void walk##R(int x0, int y, int k) {                                                  \
    Column win[2 * R + 1];                                                              \
    for (int x = x0 - 2 * R; x < min(x0 + pc.run, pc.width); ++x) {                     \
      [[unroll]] for (int m = 0; m < 2 * R; ++m) win[m] = win[m + 1];                   \
      win[2 * R] = column(x + R, y, k, R);                                              \
      if (x < x0) continue;                                                             \
      float cost = kNoCost;                                                             \
      if (masked(pc.mask, pc.width, pc.height, x, y)) {                                 \
        precise float n = 0.0, s0 = 0.0, s1 = 0.0, s00 = 0.0, s11 = 0.0, s01 = 0.0;     \
        [[unroll]] for (int m = 0; m < 2 * R + 1; ++m) {                                \
          n += win[m].n;                                                                \
          s0 += win[m].s0;                                                              \
          s1 += win[m].s1;                                                              \
          s00 += win[m].s00;                                                            \
          s11 += win[m].s11;                                                            \
          s01 += win[m].s01;                                                            \
        }                                                                               \
        cost = zncc(n, s0, s1, s00, s11, s01, 2 * R + 1);                               \
      }                                                                                 \
      pc.costs.v[idx(pc.width, pc.planes, x, y, k)] = cost;                             \
    }                                                                                   \
  }
WALK(0)
WALK(1)
WALK(2)
WALK(3)
WALK(4)

// Radii beyond walk's (kMaxRadius): every window from its columns afresh, in the same
// order. A wider register window would cost every radius registers (one allocation for
// the whole shader) and with them occupancy.
void direct(int r, int x0, int y, int k) {
  for (int x = x0; x < min(x0 + pc.run, pc.width); ++x) {
    float cost = kNoCost;
    if (masked(pc.mask, pc.width, pc.height, x, y)) {
      precise float n = 0.0, s0 = 0.0, s1 = 0.0, s00 = 0.0, s11 = 0.0, s01 = 0.0;
      for (int dx = -r; dx <= r; ++dx) {
        const Column c = column(x + dx, y, k, r);
        n += c.n;
        s0 += c.s0;
        s1 += c.s1;
        s00 += c.s00;
        s11 += c.s11;
        s01 += c.s01;
      }
      cost = zncc(n, s0, s1, s00, s11, s01, 2 * r + 1);
    }
    pc.costs.v[idx(pc.width, pc.planes, x, y, k)] = cost;
  }
}

void main() {
  const int i = int(gl_GlobalInvocationID.x), y = int(gl_WorkGroupID.y);
  const int runs = (pc.width + pc.run - 1) / pc.run;
  if (i >= runs * pc.planes || y >= pc.height) return;
  const int run = i / pc.planes, k = i - run * pc.planes;
  const int x0 = run * pc.run;
  switch (pc.radius) {
    case 0: walk0(x0, y, k); break;
    case 1: walk1(x0, y, k); break;
    case 2: walk2(x0, y, k); break;
    case 3: walk3(x0, y, k); break;
    case 4: walk4(x0, y, k); break;
    default: direct(pc.radius, x0, y, k); break;
  }
}

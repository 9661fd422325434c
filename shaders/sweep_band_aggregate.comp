#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#ifdef CS_J
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_shuffle : require
#endif
// One scanline direction of the band sweep's semi-global aggregation
// (backend_cpu/plane_sweep.cpp aggregateDirection with Bands / sweepBandAggregate). As
// sweep_aggregate.comp, all four directions run in one dispatch (gl_WorkGroupID.y = 0..3 =
// +x, -x, +y, -y), +x writing its path costs into `aggregated`, the others into `spare`'s
// three volumes (L at pixels with a band, 0 elsewhere), and sweep_combine.comp adds them in
// the oracle's order.
// A band holds at most kMaxBand = 32 hypotheses, so a line is walked by 32 invocations:
// invocation k takes hypothesis first + k of the current pixel (those past the band idle).
// The previous pixel's path costs sit in shared memory, shifted against the current band
// by the difference of the two firsts: a neighbour's terms are read where its band holds
// them (the oracle omits the rest). One barrier a step publishes the step's path costs,
// from which every invocation takes m (the minimum: order-free, exact; the idle
// invocations publish +inf, so the 32 reads need no test and overlap). Barriers are
// work-group wide, so a group's kLines lines (all of one direction, the same length) walk
// in lockstep; the lines past the last one walk the last one's data without writing. One
// line a group: a one-subgroup barrier is cheap where the subgroup holds 32 invocations,
// and no line waits on another's loads.
// Work groups: (ceil(max(width, height) / kLines), 4).
//
// With -DCS_J=J (devices with subgroup arithmetic and shuffles in compute shaders and
// subgroups of 32 / J invocations, J = 1, 2, 4 or 8) a line is one subgroup's, a work group
// of it alone: lane l holds hypotheses l + S j (S the subgroup size, j < J), the previous
// step's path costs stay in registers, the neighbours' terms and m (a butterfly) come by
// shuffles: no shared memory and no barrier in the step loop. A device whose subgroups are
// not the size it reports walks the same way with the path costs in shared memory and a
// barrier a step.
#define CS_OWN_WORK_GROUP
#include "common.glsl"

// A cost above 1 (anticorrelated windows) says no more than "no match" (the oracle's
// kCostCap).
const float kCostCap = 1.0;
const int kMaxBand = 32;  // kMaxSweepBand (backend_vulkan/kernels.cpp checks)
const int kLines = 1;     // mirrors kSweepBandAggregateLines in backend_vulkan/kernels.cpp
#ifdef CS_J
const int kGroup = kMaxBand / CS_J;  // a line's invocations: its subgroup
layout(local_size_x = kGroup, local_size_y = 1, local_size_z = 1) in;
#else
layout(local_size_x = kMaxBand, local_size_y = kLines, local_size_z = 1) in;
#endif

layout(push_constant) uniform PC {
  FBuf aggregated, spare, costs, first, mask;  // aggregated, costs: `band` channels; spare: 3 volumes
  int width, height, band;
  float p1, p2;  // penalty of a step to a neighbouring hypothesis, of any larger jump
} pc;

// A line of a direction: pixel start + step * stride (y * width + x) at each step, and
// where its path costs go (paths.v[offset + pixel * band + k]).
struct Line {
  int start, stride, steps, offset;
  FBuf paths;
};

// Line `line` (< the direction's lines) of `direction` (0: +x, 1: -x, 2: +y, 3: -y).
Line lineOf(int direction, int line) {
  const int w = pc.width, h = pc.height;
  const bool alongRows = direction < 2;
  Line l;
  l.steps = alongRows ? w : h;
  const int along = alongRows ? 1 : w;  // one step forward, in pixels
  const int first = alongRows ? line * w : line;
  const bool forward = direction == 0 || direction == 2;
  l.start = forward ? first : first + (l.steps - 1) * along;
  l.stride = forward ? along : -along;
  l.offset = direction == 0 ? 0 : (direction - 1) * w * h * pc.band;
  l.paths = direction == 0 ? pc.aggregated : pc.spare;
  return l;
}

#ifndef CS_J
// The path costs of the last two steps with a band, per line (ping-pong: a step writes
// path[parity] and reads path[parity ^ 1]; the barrier between two steps keeps the one
// that writes a half after every read of it).
shared float path[2][kLines][kMaxBand];

#endif

// The walk's state between steps (the same in all of a line's invocations).
struct Walk {
  bool havePrevious;
  float previousMin;
  int previousFirst, parity;
};

#ifndef CS_J
// One step of a line with the pixel's mask, first and this invocation's cost in hand.
void walkStep(Line ln, bool writes, int s, float inMask, float firstValue, float cost, inout Walk walk) {
  const int k = int(gl_LocalInvocationID.x), line = int(gl_LocalInvocationID.y);
  const int first = int(firstValue);
  const bool banded = inMask != 0.0 && first >= 0;  // else the path ends here (aggregated 0)
  const bool mine = k < pc.band;
  const int at = ln.offset + (ln.start + s * ln.stride) * pc.band + k;
  if (banded && !mine) {
    path[walk.parity][line][k] = posInf();
  } else if (banded) {
    const float c = min(cost, kCostCap);
    float l = c;
    if (walk.havePrevious) {
      // The oracle's operations in its order: v = m + p2, then L(j), L(j - 1) + p1,
      // L(j + 1) + p1 where the previous band holds them; (c + v) - m.
      const int j = k + first - walk.previousFirst, prev = walk.parity ^ 1;
      precise float v = walk.previousMin + pc.p2;
      if (j >= 0 && j < pc.band) v = min(path[prev][line][j], v);
      if (j - 1 >= 0 && j - 1 < pc.band) v = min(v, path[prev][line][j - 1] + pc.p1);
      if (j + 1 >= 0 && j + 1 < pc.band) v = min(v, path[prev][line][j + 1] + pc.p1);
      precise float sum = (c + v) - walk.previousMin;
      l = sum;
    }
    path[walk.parity][line][k] = l;
    if (writes) ln.paths.v[at] = l;
  } else if (mine && writes) {
    ln.paths.v[at] = 0.0;
  }
  barrier();
  if (banded) {
    // Four independent chains of minima: the reads do not wait on each other.
    float m[4];
    [[unroll]] for (int i = 0; i < 4; ++i) m[i] = path[walk.parity][line][i];
    [[unroll]] for (int i = 4; i < kMaxBand; ++i) m[i % 4] = min(m[i % 4], path[walk.parity][line][i]);
    walk.previousMin = min(min(m[0], m[1]), min(m[2], m[3]));
    walk.previousFirst = first;
    walk.parity ^= 1;
  }
  walk.havePrevious = banded;
}

// A step takes a hundred or two cycles, a load from memory about a microsecond: each
// step's mask, first and cost are loaded kSlots - 1 steps ahead into a ring of registers, the
// step loop unrolled by kSlots so that every slot index is a constant (as
// sweep_aggregate.comp's walkSubgroup).
const int kSlots = 12;

void main() {
  const int direction = int(gl_WorkGroupID.y);
  const int lines = direction < 2 ? pc.height : pc.width;
  const int line0 = int(gl_WorkGroupID.x) * kLines;
  if (line0 >= lines) return;  // the whole group: barriers stay in uniform control flow
  const int line = line0 + int(gl_LocalInvocationID.y);
  const bool writes = line < lines;
  Line ln = lineOf(direction, min(line, lines - 1));
  const int kLoad = min(int(gl_LocalInvocationID.x), pc.band - 1);  // idle invocations load a valid address
  float ringMask[kSlots], ringFirst[kSlots], ringCost[kSlots];
  [[unroll]] for (int d = 0; d + 1 < kSlots; ++d) {
    if (d < ln.steps) {
      const int pixel = ln.start + d * ln.stride;
      ringMask[d] = pc.mask.v[pixel];
      ringFirst[d] = pc.first.v[pixel];
      ringCost[d] = pc.costs.v[pixel * pc.band + kLoad];
    }
  }
  Walk walk = Walk(false, 0.0, 0, 0);
  for (int s0 = 0; s0 < ln.steps; s0 += kSlots) {
    [[unroll]] for (int d = 0; d < kSlots; ++d) {
      const int s = s0 + d;
      if (s >= ln.steps) break;  // uniform: every line of a group has the same length
      const int ahead = s + kSlots - 1, slot = (d + kSlots - 1) % kSlots;
      if (ahead < ln.steps) {
        const int pixel = ln.start + ahead * ln.stride;
        ringMask[slot] = pc.mask.v[pixel];
        ringFirst[slot] = pc.first.v[pixel];
        ringCost[slot] = pc.costs.v[pixel * pc.band + kLoad];
      }
      walkStep(ln, writes, s, ringMask[d], ringFirst[d], ringCost[d], walk);
    }
  }
}
#endif

#ifdef CS_J
// ---- a line per subgroup ----

// The previous step's path costs, published for the neighbours where the subgroups are
// not kGroup invocations (ping-pong halves as path[] above).
shared float published[2][kMaxBand];

// The previous step's path cost of hypothesis q (0 <= q < kMaxBand, clamped: the caller
// uses it only where the previous band holds q): from lane q % kGroup's chunk q / kGroup.
float fetch(float held[CS_J], int q, bool shuffles, int parity) {
  const int qc = clamp(q, 0, kMaxBand - 1);
  if (!shuffles) return published[parity][qc];
  const uint lane = uint(qc % kGroup);
  const int chunk = qc / kGroup;
  float v = 0.0;
  [[unroll]] for (int j = 0; j < CS_J; ++j) {
    const float s = subgroupShuffle(held[j], lane);
    if (chunk == j) v = s;
  }
  return v;
}

// One step of a line with the pixel's mask, first and this invocation's costs in hand
// (held: the last banded step's path costs of hypotheses lane + kGroup j, +inf past the
// band). shuffles: the subgroup is the work group (uniform), else through shared memory.
void walkStepSubgroup(Line ln, bool shuffles, int s, float inMask, float firstValue, float cost[CS_J],
                      inout float held[CS_J], inout Walk walk) {
  const int lane = int(gl_LocalInvocationID.x);
  const int first = int(firstValue);
  const bool banded = inMask != 0.0 && first >= 0;  // else the path ends here (aggregated 0)
  const int at = ln.offset + (ln.start + s * ln.stride) * pc.band;
  if (!banded) {
    [[unroll]] for (int j = 0; j < CS_J; ++j)
      if (lane + kGroup * j < pc.band) ln.paths.v[at + lane + kGroup * j] = 0.0;
    walk.havePrevious = false;
    return;
  }
  float l[CS_J];
  const int shift = first - walk.previousFirst, prev = walk.parity ^ 1;
  [[unroll]] for (int j = 0; j < CS_J; ++j) {
    const int k = lane + kGroup * j;
    const float c = min(cost[j], kCostCap);
    l[j] = c;
    if (walk.havePrevious) {
      // The oracle's operations in its order: v = m + p2, then L(i), L(i - 1) + p1,
      // L(i + 1) + p1 where the previous band holds them; (c + v) - m.
      const int i = k + shift;
      const float same = fetch(held, i, shuffles, prev), below = fetch(held, i - 1, shuffles, prev),
                  above = fetch(held, i + 1, shuffles, prev);
      precise float v = walk.previousMin + pc.p2;
      if (i >= 0 && i < pc.band) v = min(same, v);
      if (i - 1 >= 0 && i - 1 < pc.band) v = min(v, below + pc.p1);
      if (i + 1 >= 0 && i + 1 < pc.band) v = min(v, above + pc.p1);
      precise float sum = (c + v) - walk.previousMin;
      l[j] = sum;
    }
  }
  float lowest = posInf();
  [[unroll]] for (int j = 0; j < CS_J; ++j) {
    const int k = lane + kGroup * j;
    const bool mine = k < pc.band;
    held[j] = mine ? l[j] : posInf();
    lowest = min(lowest, held[j]);
    if (mine) ln.paths.v[at + k] = l[j];
  }
  if (shuffles) {
    // A butterfly of shuffles (min is exact in any order, as the oracle's running minimum),
    // unrolled: measured on an H200 (NVIDIA 580), the band aggregation took 0.27 ms so,
    // 0.50 with subgroupMin and 0.31 with the path costs in shared memory and a barrier.
    [[unroll]] for (int o = kGroup / 2; o > 0; o /= 2) lowest = min(lowest, subgroupShuffleXor(lowest, uint(o)));
    walk.previousMin = lowest;
  } else {
    [[unroll]] for (int j = 0; j < CS_J; ++j) published[walk.parity][lane + kGroup * j] = held[j];
    barrier();
    float m = published[walk.parity][0];
    for (int i = 1; i < kMaxBand; ++i) m = min(m, published[walk.parity][i]);
    walk.previousMin = m;
  }
  walk.previousFirst = first;
  walk.parity ^= 1;
  walk.havePrevious = true;
}

// Loads kSlots - 1 steps ahead, as the walk above.
const int kSlots = 12;

void main() {
  const int direction = int(gl_WorkGroupID.y);
  const int lines = direction < 2 ? pc.height : pc.width;
  const int line = int(gl_WorkGroupID.x);
  if (line >= lines) return;  // the whole group
  const bool shuffles = gl_SubgroupSize == uint(kGroup) && gl_NumSubgroups == 1u;
  const int lane = int(gl_LocalInvocationID.x);
  Line ln = lineOf(direction, line);
  float held[CS_J];
  [[unroll]] for (int j = 0; j < CS_J; ++j) held[j] = posInf();
  float ringMask[kSlots], ringFirst[kSlots], ringCost[kSlots][CS_J];
  [[unroll]] for (int d = 0; d + 1 < kSlots; ++d) {
    if (d < ln.steps) {
      const int pixel = ln.start + d * ln.stride;
      ringMask[d] = pc.mask.v[pixel];
      ringFirst[d] = pc.first.v[pixel];
      // Lanes past the band load a valid address.
      [[unroll]] for (int j = 0; j < CS_J; ++j)
        ringCost[d][j] = pc.costs.v[pixel * pc.band + min(lane + kGroup * j, pc.band - 1)];
    }
  }
  Walk walk = Walk(false, 0.0, 0, 0);
  for (int s0 = 0; s0 < ln.steps; s0 += kSlots) {
    [[unroll]] for (int d = 0; d < kSlots; ++d) {
      const int s = s0 + d;
      if (s >= ln.steps) break;
      const int ahead = s + kSlots - 1, slot = (d + kSlots - 1) % kSlots;
      if (ahead < ln.steps) {
        const int pixel = ln.start + ahead * ln.stride;
        ringMask[slot] = pc.mask.v[pixel];
        ringFirst[slot] = pc.first.v[pixel];
        [[unroll]] for (int j = 0; j < CS_J; ++j)
          ringCost[slot][j] = pc.costs.v[pixel * pc.band + min(lane + kGroup * j, pc.band - 1)];
      }
      walkStepSubgroup(ln, shuffles, s, ringMask[d], ringFirst[d], ringCost[d], held, walk);
    }
  }
}
#endif

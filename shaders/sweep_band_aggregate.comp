#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
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
#define CS_OWN_WORK_GROUP
#include "common.glsl"

// A cost above 1 (anticorrelated windows) says no more than "no match" (the oracle's
// kCostCap).
const float kCostCap = 1.0;
const int kMaxBand = 32;  // kMaxSweepBand (backend_vulkan/kernels.cpp checks)
const int kLines = 1;     // mirrors kSweepBandAggregateLines in backend_vulkan/kernels.cpp
layout(local_size_x = kMaxBand, local_size_y = kLines, local_size_z = 1) in;

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

// The path costs of the last two steps with a band, per line (ping-pong: a step writes
// path[parity] and reads path[parity ^ 1]; the barrier between two steps keeps the one
// that writes a half after every read of it).
shared float path[2][kLines][kMaxBand];

// The walk's state between steps (the same in all of a line's invocations).
struct Walk {
  bool havePrevious;
  float previousMin;
  int previousFirst, parity;
};

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

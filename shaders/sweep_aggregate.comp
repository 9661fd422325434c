#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#ifdef CS_SUBGROUP
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_memory_scope_semantics : require
#endif
// One scanline direction of the semi-global aggregation of the plane-sweep costs
// (backend_cpu/plane_sweep.cpp aggregateDirection / sweepAggregate). All four directions
// run in one dispatch, gl_WorkGroupID.y = 0..3 = +x, -x, +y, -y, each writing its own path
// costs (L at masked pixels, 0 elsewhere): +x into `aggregated`, the others into `spare`
// (three volumes one after the other). sweep_combine.comp then adds them in the
// oracle's order ((L_+x + L_-x) + L_+y) + L_-y. A walk is a chain of dependent steps, so
// four side by side keep the GPU busier than four one after the other.
//
// Along a line each pixel's path costs depend on the previous pixel's, so a line is
// walked step by step; within a step the planes are independent except for m, the
// minimum of the previous step's path costs. Work groups: (max(width, height), 4).
//
// With -DCS_SUBGROUP (devices with subgroup arithmetic in compute shaders) a line is one
// subgroup's (walkSubgroup): each invocation holds J consecutive planes in registers, m is
// a subgroupMin, the neighbours across invocations pass through shared memory with a
// subgroup barrier: no work-group barrier in the step loop, and each step's costs load
// kSlots - 1 steps ahead. Work group x takes lines x * subgroups ..; the
// groups past the last line return at once. Planes beyond kMaxJ per invocation (a
// small subgroup) and the build without subgroups walk a line with the whole work group
// (walkGroup): plane k on invocation k % kGroupSize, the previous step's path costs in
// shared memory, m from a reduction (subgroupMin of each subgroup, then the few minima;
// a shared-memory tree without subgroups), barriers at every step.
#define CS_OWN_WORK_GROUP
#include "common.glsl"

// A cost above 1 (anticorrelated windows) says no more than "no match" (the oracle's
// kCostCap).
const float kCostCap = 1.0;
#ifdef CS_SUBGROUP
const int kGroupSize = 64;  // a few lines per group: the few walks spread over more SMs
#else
const int kGroupSize = 256;
#endif
layout(local_size_x = kGroupSize, local_size_y = 1, local_size_z = 1) in;
const int kMaxPlanes = 512;  // kMaxSweepPlanes (backend_vulkan/kernels.cpp checks)
const int kMaxJ = 8;         // planes per invocation in walkSubgroup (256 at subgroup size 32)

layout(push_constant) uniform PC {
  FBuf aggregated, spare, costs, mask;  // aggregated, costs: `planes` channels; spare: 3 volumes
  int width, height, planes;
  float p1, p2;  // penalty of a step to a neighbouring plane, of any larger jump
} pc;

// A line of a direction: pixel start + step * stride (y * width + x) at each step, and
// where its path costs go (paths.v[offset + pixel * planes + k]).
struct Line {
  int start, stride, steps, offset;
  FBuf paths;
};

// Line `line` of `direction` (0: +x, 1: -x, 2: +y, 3: -y); false past the last line.
bool lineOf(int direction, int line, out Line l) {
  const int w = pc.width, h = pc.height;
  const bool alongRows = direction < 2;
  if (line >= (alongRows ? h : w)) return false;
  l.steps = alongRows ? w : h;
  const int along = alongRows ? 1 : w;  // one step forward, in pixels
  const int first = alongRows ? line * w : line;
  const bool forward = direction == 0 || direction == 2;
  l.start = forward ? first : first + (l.steps - 1) * along;
  l.stride = forward ? along : -along;
  l.offset = direction == 0 ? 0 : (direction - 1) * w * h * pc.planes;
  l.paths = direction == 0 ? pc.aggregated : pc.spare;
  return true;
}

// One path cost in the oracle's operations and order (precise: no fused or reassociated
// adds). c: the capped cost; same, below, above: the previous step's L at k, k - 1, k + 1.
float pathCost(float c, float same, float below, float above, bool hasBelow, bool hasAbove, float previousMin) {
  precise float v = min(same, previousMin + pc.p2);
  if (hasBelow) v = min(v, below + pc.p1);
  if (hasAbove) v = min(v, above + pc.p1);
  precise float l = (c + v) - previousMin;
  return l;
}

// ---- a line per work group ----

// The path costs of the last two masked steps (ping-pong: step j writes path[j & 1] and
// reads path[(j - 1) & 1]), and the per-invocation minima of the reduction, likewise
// doubled so that a step's reduction never overwrites the m another invocation is still
// reading from the step before.
shared float path[2][kMaxPlanes];
shared float lowest[2][kGroupSize];

void walkGroup(Line ln) {
  const int lid = int(gl_LocalInvocationIndex);
#ifndef CS_SUBGROUP
  // The reduction's first stride: half the smallest power of two covering the invocations
  // that hold a plane (those beyond hold +inf), so few planes take few rounds.
  const int holding = min(pc.planes, kGroupSize);
  int firstStride = 1;
  while (2 * firstStride < holding) firstStride *= 2;
#endif
  bool havePrevious = false;  // uniform: every invocation walks the same pixels
  float previousMin = 0.0;
  int j = 0;  // masked steps so far since the start: selects the ping-pong halves
  for (int step = 0; step < ln.steps; ++step) {
    const int pixel = ln.start + step * ln.stride, base = pixel * pc.planes;
    if (pc.mask.v[pixel] == 0.0) {
      // The path restarts after an unmasked pixel; aggregated is 0 there.
      havePrevious = false;
      for (int k = lid; k < pc.planes; k += kGroupSize) ln.paths.v[ln.offset + base + k] = 0.0;
      continue;
    }
    const int cur = j & 1, prev = cur ^ 1;
    float localMin = posInf();
    for (int k = lid; k < pc.planes; k += kGroupSize) {
      const float c = min(pc.costs.v[base + k], kCostCap);
      float l = c;
      if (havePrevious)
        l = pathCost(c, path[prev][k], path[prev][max(k - 1, 0)], path[prev][min(k + 1, pc.planes - 1)], k > 0,
                     k + 1 < pc.planes, previousMin);
      path[cur][k] = l;
      localMin = min(localMin, l);
      ln.paths.v[ln.offset + base + k] = l;
    }
    // m = the minimum of this step's path costs (order-free: min is exact). The first
    // barrier also publishes path[cur] for the next step's neighbours k -+ 1.
#ifdef CS_SUBGROUP
    const float subgroupLowest = subgroupMin(localMin);
    if (subgroupElect()) lowest[cur][gl_SubgroupID] = subgroupLowest;
    barrier();
    previousMin = lowest[cur][0];
    for (uint s = 1u; s < gl_NumSubgroups; ++s) previousMin = min(previousMin, lowest[cur][s]);
#else
    lowest[cur][lid] = localMin;
    barrier();
    for (int stride = firstStride; stride > 0; stride /= 2) {
      if (lid < stride) lowest[cur][lid] = min(lowest[cur][lid], lowest[cur][lid + stride]);
      barrier();
    }
    previousMin = lowest[cur][0];
#endif
    havePrevious = true;
    ++j;
  }
}

#ifdef CS_SUBGROUP
// ---- a line per subgroup ----

// Each invocation's first and last path cost of the last two masked steps (ping-pong as
// path[]), for the neighbouring invocations' planes k -+ 1 across the seam.
shared float edges[2][2][kGroupSize];  // [step parity][0: first, 1: last][invocation]

// One masked or unmasked step of a line with its costs c and mask value in hand.
void subgroupStep(Line ln, int J, int k0, int e, int step, float c[kMaxJ], float inMask, inout float held[kMaxJ],
                  inout bool havePrevious, inout float previousMin, inout int parity) {
  const int base = (ln.start + step * ln.stride) * pc.planes;
  if (inMask == 0.0) {
    // The path restarts after an unmasked pixel; aggregated is 0 there.
    havePrevious = false;
    [[unroll]] for (int j = 0; j < kMaxJ; ++j)
      if (j < J && k0 + j < pc.planes) ln.paths.v[ln.offset + base + k0 + j] = 0.0;
    return;
  }
  // The neighbours' seam values from the last masked step (read only when they exist).
  const float below = havePrevious && k0 > 0 ? edges[parity ^ 1][1][e - 1] : 0.0;
  const float above = havePrevious && k0 + J < pc.planes ? edges[parity ^ 1][0][e + 1] : 0.0;
  float localMin = posInf(), belowHeld = below;  // belowHeld: held[j - 1] before this step
  [[unroll]] for (int j = 0; j < kMaxJ; ++j) {
    const int k = k0 + j;
    if (j < J && k < pc.planes) {
      const float cc = min(c[j], kCostCap);
      float l = cc;
      if (havePrevious) {
        const float up = j + 1 < J ? held[min(j + 1, kMaxJ - 1)] : above;
        l = pathCost(cc, held[j], belowHeld, up, k > 0, k + 1 < pc.planes, previousMin);
      }
      belowHeld = held[j];
      held[j] = l;
      localMin = min(localMin, l);
      ln.paths.v[ln.offset + base + k] = l;
      if (j == 0) edges[parity][0][e] = l;
      if (j == J - 1) edges[parity][1][e] = l;
    }
  }
  previousMin = subgroupMin(localMin);  // exact, as the oracle's running minimum
  controlBarrier(gl_ScopeSubgroup, gl_ScopeSubgroup, gl_StorageSemanticsShared, gl_SemanticsAcquireRelease);
  havePrevious = true;
  parity ^= 1;
}

// A step takes a few hundred cycles, a load from memory under this traffic about a
// microsecond: each step's costs and mask are loaded kSlots - 1 steps ahead into a ring
// of registers. The step loop is unrolled by kSlots so that every slot index is a
// constant; the slot refilled at step s is the one step s - 1 consumed, so no register
// waits on a load before its step (the mask is compared only when its step runs).
const int kSlots = 6;

void walkSubgroup(Line ln, int J) {
  const int lane = int(gl_SubgroupInvocationID), S = int(gl_SubgroupSize);
  const int e = int(gl_SubgroupID) * S + lane;  // this invocation's edges[][][e]
  const int k0 = lane * J;                      // planes k0 .. k0 + J - 1 (those < planes)
  const int kLoad = min(k0, pc.planes - 1);     // spare invocations load a valid address
  float held[kMaxJ];                            // the last masked step's path costs
  float ringCost[kSlots][kMaxJ], ringMask[kSlots];
  [[unroll]] for (int d = 0; d + 1 < kSlots; ++d) {
    if (d < ln.steps) {
      const int pixel = ln.start + d * ln.stride;
      ringMask[d] = pc.mask.v[pixel];
      [[unroll]] for (int j = 0; j < kMaxJ; ++j)
        if (j < J) ringCost[d][j] = pc.costs.v[pixel * pc.planes + min(kLoad + j, pc.planes - 1)];
    }
  }
  bool havePrevious = false;
  float previousMin = 0.0;
  int parity = 0;
  for (int step0 = 0; step0 < ln.steps; step0 += kSlots) {
    [[unroll]] for (int d = 0; d < kSlots; ++d) {
      const int step = step0 + d;
      if (step >= ln.steps) break;
      const int ahead = step + kSlots - 1, slot = (d + kSlots - 1) % kSlots;
      if (ahead < ln.steps) {
        const int pixel = ln.start + ahead * ln.stride;
        ringMask[slot] = pc.mask.v[pixel];
        [[unroll]] for (int j = 0; j < kMaxJ; ++j)
          if (j < J) ringCost[slot][j] = pc.costs.v[pixel * pc.planes + min(kLoad + j, pc.planes - 1)];
      }
      subgroupStep(ln, J, k0, e, step, ringCost[d], ringMask[d], held, havePrevious, previousMin, parity);
    }
  }
}
#endif

void main() {
  const int direction = int(gl_WorkGroupID.y);
  Line ln;
#ifdef CS_SUBGROUP
  const int J = (pc.planes + int(gl_SubgroupSize) - 1) / int(gl_SubgroupSize);
  if (J <= kMaxJ) {
    const int line = int(gl_WorkGroupID.x * gl_NumSubgroups + gl_SubgroupID);
    if (lineOf(direction, line, ln)) walkSubgroup(ln, J);
    return;
  }
#endif
  // The whole group returns together: barriers stay in uniform control flow.
  if (lineOf(direction, int(gl_WorkGroupID.x), ln)) walkGroup(ln);
}

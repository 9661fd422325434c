#version 460
#ifdef CS_J
#define CS_SUBGROUP  // the subgroup walk of CS_J planes a lane
#endif
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#ifdef CS_SUBGROUP
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_shuffle : require
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
// With -DCS_SUBGROUP -DCS_J=J (devices with subgroup arithmetic and shuffles in compute
// shaders; the host picks J = ceil(planes / subgroup size), 1 .. 8) a line is one
// subgroup's (walkSubgroup): lane l holds planes l + S j (as backend_cuda's lanes) in
// registers, m is a subgroupMin, the neighbours pass by subgroup shuffles: no shared
// memory and no barrier in the step loop, the loads and stores of a step coalesce, and
// each step's costs load kSlots - 1 steps ahead. Work group x takes lines x * subgroups ..;
// the groups past the last line return at once. More planes (a small subgroup) and the
// build without subgroups walk a line with the whole work group (walkGroup): plane k on
// invocation k % kGroupSize, the previous step's path costs in shared memory, m from a
// reduction (subgroupMin of each subgroup, then the few minima; a shared-memory tree
// without subgroups), barriers at every step.
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

// One masked or unmasked step of a line with its costs c and mask value in hand. Lane l
// holds planes l + S j (j < CS_J, S the subgroup size): the loads and stores of a step
// coalesce, and the neighbours k -+ 1 come by a rotating shuffle (lane 0's k - 1 is the
// previous chunk's lane S - 1, lane S - 1's k + 1 the next chunk's lane 0).
void subgroupStep(Line ln, int lane, int S, int step, float c[CS_J], float inMask, inout float held[CS_J],
                  inout bool havePrevious, inout float previousMin) {
  const int base = ln.offset + (ln.start + step * ln.stride) * pc.planes;
  if (inMask == 0.0) {
    // The path restarts after an unmasked pixel; aggregated is 0 there.
    havePrevious = false;
    [[unroll]] for (int j = 0; j < CS_J; ++j)
      if (lane + S * j < pc.planes) ln.paths.v[base + lane + S * j] = 0.0;
    return;
  }
  float localMin = posInf();
  // The previous step's path costs of lanes l - 1 and l + 1 (rotating: lane 0 gets lane
  // S - 1's, lane S - 1 lane 0's, of the same chunk). The shuffles and the path costs run
  // at every step, a path's first taking its capped costs by a select (held is finite
  // there): one body a step rather than two halves the unrolled walk's code (sweep:
  // aggregate 0.33 -> 0.31 ms on the H200).
  const uint down = uint(lane == 0 ? S - 1 : lane - 1), up = uint(lane == S - 1 ? 0 : lane + 1);
  float fromDown[CS_J], fromUp[CS_J];
  [[unroll]] for (int j = 0; j < CS_J; ++j) {
    fromDown[j] = subgroupShuffle(held[j], down);
    fromUp[j] = subgroupShuffle(held[j], up);
  }
  [[unroll]] for (int j = 0; j < CS_J; ++j) {
    const int k = lane + S * j;
    const float below = lane == 0 ? (j > 0 ? fromDown[max(j - 1, 0)] : 0.0) : fromDown[j];
    const float above = lane == S - 1 ? (j + 1 < CS_J ? fromUp[min(j + 1, CS_J - 1)] : 0.0) : fromUp[j];
    const float capped = min(c[j], kCostCap);
    const float walked = pathCost(capped, held[j], below, above, k > 0, k + 1 < pc.planes, previousMin);
    const float l = havePrevious ? walked : capped;
    held[j] = l;
    if (k < pc.planes) {
      localMin = min(localMin, l);
      ln.paths.v[base + k] = l;
    }
  }
  previousMin = subgroupMin(localMin);  // exact, as the oracle's running minimum
  havePrevious = true;
}

// A step takes a few hundred cycles, a load from memory under this traffic about a
// microsecond: each step's costs and mask are loaded kSlots - 1 steps ahead into a ring
// of registers. The step loop is unrolled by kSlots so that every slot index is a
// constant; the slot refilled at step s is the one step s - 1 consumed, so no register
// waits on a load before its step (the mask is compared only when its step runs). About
// 24 registers of costs, not backend_cuda's 60: NVIDIA's Vulkan compiler gave the 12-slot
// ring of three planes a lane 82 registers and 74 KB of code, and the walk ran slower the
// longer its unrolled loop (H200, the full sweep's 66 planes: sweep: aggregate 0.39 ms
// with 12 slots, 0.46 with 16, 0.34 with 8, 0.32-0.33 with 6 or 4).
const int kSlots = 24 / CS_J < 2 ? 2 : (24 / CS_J > 12 ? 12 : 24 / CS_J);

void walkSubgroup(Line ln) {
  const int lane = int(gl_SubgroupInvocationID), S = int(gl_SubgroupSize);
  float held[CS_J];  // the last masked step's path costs of planes lane + S j
  [[unroll]] for (int j = 0; j < CS_J; ++j) held[j] = 0.0;
  float ringCost[kSlots][CS_J], ringMask[kSlots];
  [[unroll]] for (int d = 0; d + 1 < kSlots; ++d) {
    if (d < ln.steps) {
      const int pixel = ln.start + d * ln.stride;
      ringMask[d] = pc.mask.v[pixel];
      // Spare lanes load a plane they never use (a valid address).
      [[unroll]] for (int j = 0; j < CS_J; ++j)
        ringCost[d][j] = pc.costs.v[pixel * pc.planes + min(lane + S * j, pc.planes - 1)];
    }
  }
  bool havePrevious = false;
  float previousMin = 0.0;
  for (int step0 = 0; step0 < ln.steps; step0 += kSlots) {
    [[unroll]] for (int d = 0; d < kSlots; ++d) {
      const int step = step0 + d;
      if (step >= ln.steps) break;
      const int ahead = step + kSlots - 1, slot = (d + kSlots - 1) % kSlots;
      if (ahead < ln.steps) {
        const int pixel = ln.start + ahead * ln.stride;
        ringMask[slot] = pc.mask.v[pixel];
        [[unroll]] for (int j = 0; j < CS_J; ++j)
          ringCost[slot][j] = pc.costs.v[pixel * pc.planes + min(lane + S * j, pc.planes - 1)];
      }
      subgroupStep(ln, lane, S, step, ringCost[d], ringMask[d], held, havePrevious, previousMin);
    }
  }
}
#endif

void main() {
  const int direction = int(gl_WorkGroupID.y);
  Line ln;
#ifdef CS_SUBGROUP
  // The host picks the variant of CS_J = ceil(planes / subgroup size); a device whose
  // subgroups differ from its reported size walks a line with the whole group.
  const int J = (pc.planes + int(gl_SubgroupSize) - 1) / int(gl_SubgroupSize);
  if (J == CS_J && kGroupSize % int(gl_SubgroupSize) == 0) {
    const int line = int(gl_WorkGroupID.x * gl_NumSubgroups + gl_SubgroupID);
    if (lineOf(direction, line, ln)) walkSubgroup(ln);
    return;
  }
#endif
  // The whole group returns together: barriers stay in uniform control flow.
  if (lineOf(direction, int(gl_WorkGroupID.x), ln)) walkGroup(ln);
}

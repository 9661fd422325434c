#version 460
#extension GL_GOOGLE_include_directive : require
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
// minimum of the previous step's path costs. Hence one work group per line (work groups:
// (lines, 1)), its 256 invocations over the planes (plane k on invocation k % 256, so
// neighbouring invocations touch neighbouring floats of the interleaved buffers), the
// previous step's path costs in shared memory and m from a shared-memory reduction.
// With -DCS_SUBGROUP (devices with subgroup arithmetic in compute shaders) m is each
// subgroup's subgroupMin, then the minimum of those few: one barrier a step instead of
// one per halving of the tree.
#include "common.glsl"
#ifdef CS_SUBGROUP
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#endif

// A cost above 1 (anticorrelated windows) says no more than "no match" (the oracle's
// kCostCap).
const float kCostCap = 1.0;
const int kGroupSize = 256;   // the 16 x 16 work group of common.glsl, as a line
const int kMaxPlanes = 1024;  // the backend refuses more (shared memory: 2 x 4 KiB)

layout(push_constant) uniform PC {
  FBuf aggregated, spare, costs, mask;  // aggregated, costs: `planes` channels; spare: 3 volumes
  int width, height, planes;
  float p1, p2;  // penalty of a step to a neighbouring plane, of any larger jump
} pc;

// The path costs of the last two masked steps (ping-pong: step j writes path[j & 1] and
// reads path[(j - 1) & 1]), and the per-invocation minima of the reduction, likewise
// doubled so that a step's reduction never overwrites the m another invocation is still
// reading from the step before.
shared float path[2][kMaxPlanes];
shared float lowest[2][kGroupSize];

void main() {
  const int lid = int(gl_LocalInvocationIndex);
  const int line = int(gl_WorkGroupID.x);
  const int direction = int(gl_WorkGroupID.y);  // 0: +x, 1: -x, 2: +y, 3: -y
  const bool alongRows = direction < 2;
  const bool forward = direction == 0 || direction == 2;
  FBuf paths = direction == 0 ? pc.aggregated : pc.spare;
  const int volume = pc.width * pc.height * pc.planes;
  const int offset = direction == 0 ? 0 : (direction - 1) * volume;
  const int lines = alongRows ? pc.height : pc.width;
  const int length = alongRows ? pc.width : pc.height;
  if (line >= lines) return;  // the whole group: barriers stay in uniform control flow

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
  for (int step = 0; step < length; ++step) {
    const int along = forward ? step : length - 1 - step;
    const int x = alongRows ? along : line, y = alongRows ? line : along;
    const int base = idx(pc.width, pc.planes, x, y, 0);
    if (!masked(pc.mask, pc.width, pc.height, x, y)) {
      // The path restarts after an unmasked pixel; aggregated is 0 there.
      havePrevious = false;
      for (int k = lid; k < pc.planes; k += kGroupSize) paths.v[offset + base + k] = 0.0;
      continue;
    }
    const int cur = j & 1, prev = cur ^ 1;
    float localMin = posInf();
    for (int k = lid; k < pc.planes; k += kGroupSize) {
      const float c = min(pc.costs.v[base + k], kCostCap);
      // The oracle's operations in its order: no fused or reassociated adds.
      precise float l = c;
      if (havePrevious) {
        precise float v = min(path[prev][k], previousMin + pc.p2);
        if (k > 0) v = min(v, path[prev][k - 1] + pc.p1);
        if (k + 1 < pc.planes) v = min(v, path[prev][k + 1] + pc.p1);
        l = (c + v) - previousMin;
      }
      path[cur][k] = l;
      localMin = min(localMin, l);
      paths.v[offset + base + k] = l;
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

#version 460
#extension GL_GOOGLE_include_directive : require
// The semi-global aggregation's sum (backend_cpu/plane_sweep.cpp sweepAggregate): the four
// directions' path costs that sweep_aggregate.comp wrote side by side, added in the
// oracle's order, aggregated = ((L_+x + L_-x) + L_+y) + L_-y, L_+x being `aggregated`
// itself and the others `spare`'s three volumes. 0 outside the mask, where all four are 0.
// One invocation per four floats, work groups (ceil(count / 1024), 1): the sum is bound by
// memory, and a 16-byte access moves four floats for one instruction (backend_cuda's sum
// runs at ~80 % of the DRAM peak). The vector accesses need every volume 16-byte aligned:
// buffers start so (memory.cpp), and so do spare's later volumes where count is a
// multiple of 4; otherwise the floats go one by one.
#define CS_OWN_WORK_GROUP
#include "common.glsl"
layout(local_size_x = 256, local_size_y = 1, local_size_z = 1) in;

layout(buffer_reference, std430, buffer_reference_align = 16) buffer V4Buf { vec4 v[]; };

layout(push_constant) uniform PC {
  FBuf aggregated, spare;
  int count;  // floats in one volume
} pc;

// Four floats from i = 4 q, volume by volume; vector lanes add independently, in order.
void sumQuad(int q) {
  V4Buf a = V4Buf(pc.aggregated), s = V4Buf(pc.spare);
  const int n = pc.count / 4;
  precise vec4 sum = a.v[q] + s.v[q];
  sum = sum + s.v[q + n];
  sum = sum + s.v[q + 2 * n];
  a.v[q] = sum;
}

void sumOne(int i) {
  precise float sum = pc.aggregated.v[i] + pc.spare.v[i];
  sum = sum + pc.spare.v[i + pc.count];
  sum = sum + pc.spare.v[i + 2 * pc.count];
  pc.aggregated.v[i] = sum;
}

void main() {
  const int q = int(gl_WorkGroupID.x * 256u + gl_LocalInvocationIndex);
  if (4 * q >= pc.count) return;
  if (pc.count % 4 == 0) {
    sumQuad(q);
  } else {
    for (int i = 4 * q; i < min(4 * q + 4, pc.count); ++i) sumOne(i);
  }
}

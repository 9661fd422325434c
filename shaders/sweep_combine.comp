#version 460
#extension GL_GOOGLE_include_directive : require
// The semi-global aggregation's sum (backend_cpu/plane_sweep.cpp sweepAggregate): the four
// directions' path costs that sweep_aggregate.comp wrote side by side, added in the
// oracle's order, aggregated = ((L_+x + L_-x) + L_+y) + L_-y, L_+x being `aggregated`
// itself and the others `spare`'s three volumes. 0 outside the mask, where all four are 0.
// One invocation per float, work groups (ceil(count / 256), 1).
#include "common.glsl"

layout(push_constant) uniform PC {
  FBuf aggregated, spare;
  int count;  // floats in one volume
} pc;

void main() {
  const int i = int(gl_WorkGroupID.x * 256u + gl_LocalInvocationIndex);
  if (i >= pc.count) return;
  precise float sum = pc.aggregated.v[i] + pc.spare.v[i];
  sum = sum + pc.spare.v[i + pc.count];
  sum = sum + pc.spare.v[i + 2 * pc.count];
  pc.aggregated.v[i] = sum;
}

#version 460
#extension GL_GOOGLE_include_directive : require
// uploadBytes' conversion on the device: dst[i] = table[byte i of src] for i < n, table
// holding unitFromByte(v) for v = 0 .. 255 as the host computed them: the host's bits by
// construction (GLSL's division is not exact enough to recompute float(v) / 255.f).
// Four bytes an invocation: one word read, four floats written. A 256-wide work group, the
// groups in rows of gl_NumWorkGroups.x (more than 65535 groups for a large image).
#define CS_OWN_WORK_GROUP
#include "common.glsl"
layout(local_size_x = 256, local_size_y = 1, local_size_z = 1) in;

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer UBuf { uint v[]; };

layout(push_constant) uniform PC {
  FBuf dst;
  UBuf src;
  FBuf table;
  uint n;
} pc;

void main() {
  const uint quad = gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 256u + gl_GlobalInvocationID.x;
  if (quad >= (pc.n + 3u) / 4u) return;
  const uint word = pc.src.v[quad];
  const uint first = 4u * quad;
  const uint count = min(4u, pc.n - first);
  for (uint k = 0u; k < count; ++k) pc.dst.v[first + k] = pc.table.v[(word >> (8u * k)) & 255u];
}

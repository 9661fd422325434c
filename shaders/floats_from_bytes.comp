#version 460
#extension GL_GOOGLE_include_directive : require
// An 8-bit image's upload (backend.hpp uploadBytes): the bytes as the host staged them,
// four to a word, each stored as unitFromByte(v). The host's table of those 256 floats
// gives their bits exactly; GLSL's division is not exact enough to compute them.
#include "common.glsl"

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer WordBuf { uint v[]; };

layout(push_constant) uniform PC {
  FBuf dst;
  WordBuf bytes;  // count bytes, little-endian within each word
  FBuf table;     // unitFromByte(0..255)
  int rowLength, rows;  // count = rowLength * rows (a buffer's width * channels, height)
} pc;

void main() {
  const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.rowLength || y >= pc.rows) return;
  const uint i = uint(y) * uint(pc.rowLength) + uint(x);
  const uint byteValue = (pc.bytes.v[i >> 2] >> (8u * (i & 3u))) & 0xffu;
  pc.dst.v[i] = pc.table.v[byteValue];
}

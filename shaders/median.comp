#version 460
#extension GL_GOOGLE_include_directive : require
// dst = 3x3 median of src over masked neighbours; even counts take the mean of the two
// middle values (backend_cpu/median.cpp). Unmasked pixels copy src.
#include "common.glsl"

layout(push_constant) uniform PC {
  FBuf dst, src, mask;
  int w, h;
} pc;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.w || y >= pc.h) return;
  const int i = y * pc.w + x;
  if (!masked(pc.mask, pc.w, pc.h, x, y)) {
    pc.dst.v[i] = pc.src.v[i];
    return;
  }
  float values[9];
  int n = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      if (masked(pc.mask, pc.w, pc.h, x + dx, y + dy)) {
        // insertion sort as the values arrive
        float val = pc.src.v[(y + dy) * pc.w + x + dx];
        int k = n++;
        while (k > 0 && values[k - 1] > val) {
          values[k] = values[k - 1];
          --k;
        }
        values[k] = val;
      }
  float upper = values[n / 2];
  if (n % 2 == 0) upper = 0.5 * (values[n / 2 - 1] + upper);
  pc.dst.v[i] = upper;
}

#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : enable
// dst = 3x3 median of src over masked neighbours; even counts take the mean of the two
// middle values (backend_cpu/median.cpp). Unmasked pixels copy src.
// The oracle sorts the values as they arrive (a stable insertion sort); here each value's
// place in that order is counted (the values below it, and the equal ones before it), so
// the nine values stay in registers (no array indexed at run time).
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
  bool inside[9];
  int n = 0;
  [[unroll]] for (int k = 0; k < 9; ++k) {
    const int dx = k % 3 - 1, dy = k / 3 - 1;
    inside[k] = masked(pc.mask, pc.w, pc.h, x + dx, y + dy);
    values[k] = inside[k] ? pc.src.v[(y + dy) * pc.w + x + dx] : 0.0;
    n += inside[k] ? 1 : 0;
  }
  float lower = 0.0, upper = 0.0;
  [[unroll]] for (int k = 0; k < 9; ++k) {
    int place = 0;
    [[unroll]] for (int j = 0; j < 9; ++j)
      if (inside[j] && (values[j] < values[k] || (j < k && values[j] == values[k]))) ++place;
    if (inside[k] && place == n / 2) upper = values[k];
    if (inside[k] && place == n / 2 - 1) lower = values[k];
  }
  if (n % 2 == 0) upper = 0.5 * (lower + upper);
  pc.dst.v[i] = upper;
}

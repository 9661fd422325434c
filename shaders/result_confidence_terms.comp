#version 460
#extension GL_GOOGLE_include_directive : require
// The confidence's first pass (result_confidence.comp reads it; backend_cuda's
// result_confidence.cu does the same): what a pixel adds to every window that holds it,
// computed once instead of once per window (49 times with the 7x7 window). x, y: its image
// gradient where it and its four neighbours are masked (flag 1); z: its photometric
// residual where it is masked with a finite warp (flag 2); w: the flags.
#include "common.glsl"
#include "sampling.glsl"

layout(push_constant) uniform PC {
  FBuf terms, image, n0, n1, w, mask;
  int width, height;
} pc;

bool m(int x, int y) { return masked(pc.mask, pc.width, pc.height, x, y); }

void main() {
  const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  vec4 t = vec4(0.0);
  int flags = 0;
  if (m(x, y) && m(x - 1, y) && m(x + 1, y) && m(x, y - 1) && m(x, y + 1)) {
    t.x = 0.5 * (pc.image.v[i + 1] - pc.image.v[i - 1]);
    t.y = 0.5 * (pc.image.v[i + pc.width] - pc.image.v[i - pc.width]);
    flags |= 1;
  }
  const float wx = pc.w.v[2 * i], wy = pc.w.v[2 * i + 1];
  if (m(x, y) && !isnan(wx) && !isinf(wx) && !isnan(wy) && !isinf(wy)) {
    t.z = abs(sampleBilinear(pc.n1, pc.width, pc.height, 1, 0, float(x) + wx, float(y) + wy) - pc.n0.v[i]);
    flags |= 2;
  }
  t.w = float(flags);
  for (int k = 0; k < 4; ++k) pc.terms.v[4 * i + k] = t[k];
}

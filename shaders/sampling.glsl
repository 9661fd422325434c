// Bilinear sampling written out in arithmetic (cpu_views.hpp sampleBilinear): clamped to
// the image edge, no texture hardware.
#ifndef CS_SAMPLING_GLSL
#define CS_SAMPLING_GLSL
#include "common.glsl"

float sampleBilinear(FBuf b, int w, int h, int nc, int c, float x, float y) {
  x = min(max(x, 0.0), float(w - 1));
  y = min(max(y, 0.0), float(h - 1));
  int x0 = int(floor(x)), y0 = int(floor(y));
  int x1 = min(x0 + 1, w - 1), y1 = min(y0 + 1, h - 1);
  float fx = x - float(x0), fy = y - float(y0);
  float top = b.v[idx(w, nc, x0, y0, c)] * (1.0 - fx) + b.v[idx(w, nc, x1, y0, c)] * fx;
  float bottom = b.v[idx(w, nc, x0, y1, c)] * (1.0 - fx) + b.v[idx(w, nc, x1, y1, c)] * fx;
  return top * (1.0 - fy) + bottom * fy;
}

#endif

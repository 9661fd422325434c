// Shared by every compute shader: buffer references (all buffers are reached by device
// address from push constants), the 16x16 work group (unless a shader has its own),
// indexing and masked-grid helpers.
// Every kernel ports the CPU oracle (backend_cpu/) operation by operation.
#ifndef CS_COMMON_GLSL
#define CS_COMMON_GLSL
#extension GL_EXT_buffer_reference : require

// A shader with a work group of its own defines CS_OWN_WORK_GROUP before including this.
#ifndef CS_OWN_WORK_GROUP
layout(local_size_x = 16, local_size_y = 16, local_size_z = 1) in;
#endif

layout(buffer_reference, std430, buffer_reference_align = 4) buffer FBuf { float v[]; };

// Element (x, y, c) of a w-wide buffer with nc interleaved channels.
int idx(int w, int nc, int x, int y, int c) { return (y * w + x) * nc + c; }

bool insideGrid(int w, int h, int x, int y) { return x >= 0 && y >= 0 && x < w && y < h; }

// mask is a 1-channel w x h buffer: the pixel takes part where it is non-zero.
bool masked(FBuf mask, int w, int h, int x, int y) {
  return insideGrid(w, h, x, y) && mask.v[y * w + x] != 0.0;
}
// Forward-difference links of the masked grid (cpu_views.hpp linkX / linkY).
bool linkX(FBuf mask, int w, int h, int x, int y) { return masked(mask, w, h, x, y) && masked(mask, w, h, x + 1, y); }
bool linkY(FBuf mask, int w, int h, int x, int y) { return masked(mask, w, h, x, y) && masked(mask, w, h, x, y + 1); }

// std::lround of a float: halves away from zero (GLSL round() leaves halves open).
int lroundf(float x) {
  float a = abs(x);
  float r = floor(a);
  if (a - r >= 0.5) r += 1.0;
  return int(x < 0.0 ? -r : r);
}

float quietNaN() { return uintBitsToFloat(0x7fc00000u); }
float posInf() { return uintBitsToFloat(0x7f800000u); }

#endif

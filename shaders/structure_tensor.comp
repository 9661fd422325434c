#version 460
#extension GL_GOOGLE_include_directive : require
// Structure tensor, pass 3: D = w n n^T + n_perp n_perp^T from central differences of the
// smoothed image, w = max(exp(-beta |grad|^eta), wMin) (structure_tensor.cpp tensorAt).
#include "common.glsl"

layout(push_constant) uniform PC {
  FBuf tensor, smoothed;
  int w, h;
  float beta, eta, wMin;
} pc;

float at(int i, int j) { return pc.smoothed.v[min(max(j, 0), pc.h - 1) * pc.w + min(max(i, 0), pc.w - 1)]; }

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.w || y >= pc.h) return;
  float gx = 0.5 * (at(x + 1, y) - at(x - 1, y));
  float gy = 0.5 * (at(x, y + 1) - at(x, y - 1));
  float mag = sqrt(gx * gx + gy * gy);
  float powMag = mag > 0.0 ? pow(mag, pc.eta) : 0.0;  // pow(0, eta) is left undefined by GLSL
  float weight = max(exp(-pc.beta * powMag), pc.wMin);
  float nx = mag > 1e-12 ? gx / mag : 1.0, ny = mag > 1e-12 ? gy / mag : 0.0;
  int o = idx(pc.w, 4, x, y, 0);
  pc.tensor.v[o + 0] = weight * nx * nx + ny * ny;
  pc.tensor.v[o + 1] = (weight - 1.0) * nx * ny;
  pc.tensor.v[o + 2] = weight * ny * ny + nx * nx;
  pc.tensor.v[o + 3] = 0.0;
}

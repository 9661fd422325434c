#version 460
#extension GL_GOOGLE_include_directive : require
// Structure tensor, pass 4: the diagonal preconditioner (Pock & Chambolle 2011, alpha = 1)
// of K(u, v) = (alpha1 (D grad u - v), alpha0 grad v) on the masked grid
// (structure_tensor.cpp rowSumP1 / rowSumP2 / columnSumU).
#include "common.glsl"

layout(push_constant) uniform PC {
  FBuf steps, tensor, mask;
  int w, h;
  float alpha0, alpha1;
} pc;

float t(int x, int y, int c) { return pc.tensor.v[idx(pc.w, 4, x, y, c)]; }
bool lx(int x, int y) { return linkX(pc.mask, pc.w, pc.h, x, y); }
bool ly(int x, int y) { return linkY(pc.mask, pc.w, pc.h, x, y); }

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.w || y >= pc.h) return;
  const float kFloor = 1e-2;
  bool ex = lx(x, y), ey = ly(x, y);
  // columnSumU
  float own = abs((ex ? t(x, y, 0) : 0.0) + (ey ? t(x, y, 1) : 0.0)) +
              abs((ex ? t(x, y, 1) : 0.0) + (ey ? t(x, y, 2) : 0.0));
  float left = lx(x - 1, y) ? abs(t(x - 1, y, 0)) + abs(t(x - 1, y, 1)) : 0.0;
  float up = ly(x, y - 1) ? abs(t(x, y - 1, 1)) + abs(t(x, y - 1, 2)) : 0.0;
  float column = own + left + up;
  int links = int(ex) + int(ey) + int(lx(x - 1, y)) + int(ly(x, y - 1));
  // rowSumP1 / rowSumP2
  float d11 = ex ? t(x, y, 0) : 0.0, d12a = ey ? t(x, y, 1) : 0.0;
  float row1 = abs(d11 + d12a) + abs(d11) + abs(d12a);
  float d12b = ex ? t(x, y, 1) : 0.0, d22 = ey ? t(x, y, 2) : 0.0;
  float row2 = abs(d12b + d22) + abs(d12b) + abs(d22);
  int o = idx(pc.w, 4, x, y, 0);
  pc.steps.v[o + 0] = 1.0 / (pc.alpha1 * max(column, kFloor));
  pc.steps.v[o + 1] = 1.0 / (pc.alpha1 + pc.alpha0 * float(links));
  pc.steps.v[o + 2] = 1.0 / (pc.alpha1 * (row1 + 1.0));
  pc.steps.v[o + 3] = 1.0 / (pc.alpha1 * (row2 + 1.0));
}

#version 460
#extension GL_GOOGLE_include_directive : require
// Primal-dual iteration, primal pass: u <- prox(u + tau_u alpha1 div(D p)),
// v <- v + tau_v (alpha1 p + alpha0 div q), over-relaxed uBar, vBar at masked pixels
// (backend_cpu/primal_dual.cpp primalUpdate).
#include "primal_dual.glsl"

layout(push_constant) uniform PC {
  FBuf u, uBar, v, vBar, p, q, u0, iu, iz, tensor, steps, mask;
  int w, h;
  float tauScale, theta, lambda, alpha0, alpha1;
} pc;

bool lx(int x, int y) { return linkX(pc.mask, pc.w, pc.h, x, y); }
bool ly(int x, int y) { return linkY(pc.mask, pc.w, pc.h, x, y); }
float dpX(int x, int y) {
  int i = y * pc.w + x;
  return pc.tensor.v[4 * i] * pc.p.v[2 * i] + pc.tensor.v[4 * i + 1] * pc.p.v[2 * i + 1];
}
float dpY(int x, int y) {
  int i = y * pc.w + x;
  return pc.tensor.v[4 * i + 1] * pc.p.v[2 * i] + pc.tensor.v[4 * i + 2] * pc.p.v[2 * i + 1];
}
float qv(int x, int y, int k) { return pc.q.v[4 * (y * pc.w + x) + k]; }

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.w || y >= pc.h || !masked(pc.mask, pc.w, pc.h, x, y)) return;
  const int i = y * pc.w + x;
  const bool ex = lx(x, y), exm = lx(x - 1, y), ey = ly(x, y), eym = ly(x, y - 1);
  const float tauU = pc.tauScale * pc.steps.v[4 * i];
  const float tauV = pc.tauScale * pc.steps.v[4 * i + 1];

  float div = 0.0;
  if (ex) div += dpX(x, y);
  if (exm) div -= dpX(x - 1, y);
  if (ey) div += dpY(x, y);
  if (eym) div -= dpY(x, y - 1);
  const float uOld = pc.u.v[i];
  float uHat = uOld + tauU * pc.alpha1 * div;
  float uNew = dataProx(uHat, pc.u0.v[i], pc.iu.v[i], pc.iz.v[i], tauU * pc.lambda);
  pc.u.v[i] = uNew;
  pc.uBar.v[i] = uNew + pc.theta * (uNew - uOld);

  for (int c = 0; c < 2; ++c) {
    float d = 0.0;
    if (ex) d += qv(x, y, 2 * c);
    if (exm) d -= qv(x - 1, y, 2 * c);
    if (ey) d += qv(x, y, 2 * c + 1);
    if (eym) d -= qv(x, y - 1, 2 * c + 1);
    const float vOld = pc.v.v[2 * i + c];
    float vNew = vOld + tauV * (pc.alpha1 * pc.p.v[2 * i + c] + pc.alpha0 * d);
    pc.v.v[2 * i + c] = vNew;
    pc.vBar.v[2 * i + c] = vNew + pc.theta * (vNew - vOld);
  }
}

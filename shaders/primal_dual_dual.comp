#version 460
#extension GL_GOOGLE_include_directive : require
// Primal-dual iteration, dual pass: p <- P(p + sigma_p alpha1 (D grad uBar - vBar)),
// q <- P(q + sigma_q alpha0 grad vBar) at masked pixels (backend_cpu/primal_dual.cpp).
#include "primal_dual.glsl"

layout(push_constant) uniform PC {
  FBuf uBar, vBar, p, q, tensor, steps, mask;
  int w, h;
  float sigmaScale, alpha0, alpha1;
} pc;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.w || y >= pc.h || !masked(pc.mask, pc.w, pc.h, x, y)) return;
  const int i = y * pc.w + x;
  float gx = gradX(pc.uBar, pc.mask, pc.w, pc.h, 1, x, y, 0), gy = gradY(pc.uBar, pc.mask, pc.w, pc.h, 1, x, y, 0);
  float t0 = pc.tensor.v[4 * i], t1 = pc.tensor.v[4 * i + 1], t2 = pc.tensor.v[4 * i + 2];
  float a1 = t0 * gx + t1 * gy - pc.vBar.v[2 * i];
  float a2 = t1 * gx + t2 * gy - pc.vBar.v[2 * i + 1];
  float p0 = pc.p.v[2 * i] + pc.sigmaScale * pc.steps.v[4 * i + 2] * pc.alpha1 * a1;
  float p1 = pc.p.v[2 * i + 1] + pc.sigmaScale * pc.steps.v[4 * i + 3] * pc.alpha1 * a2;
  float norm = sqrt(p0 * p0 + p1 * p1);
  if (norm > 1.0) {
    p0 /= norm;
    p1 /= norm;
  }
  pc.p.v[2 * i] = p0;
  pc.p.v[2 * i + 1] = p1;

  const float sigmaQ = pc.sigmaScale * 0.5 / pc.alpha0;
  float q[4] = float[4](gradX(pc.vBar, pc.mask, pc.w, pc.h, 2, x, y, 0), gradY(pc.vBar, pc.mask, pc.w, pc.h, 2, x, y, 0),
                        gradX(pc.vBar, pc.mask, pc.w, pc.h, 2, x, y, 1), gradY(pc.vBar, pc.mask, pc.w, pc.h, 2, x, y, 1));
  float s = 0.0;
  for (int k = 0; k < 4; ++k) {
    q[k] = pc.q.v[4 * i + k] + sigmaQ * pc.alpha0 * q[k];
    s += q[k] * q[k];
  }
  float qn = sqrt(s);
  for (int k = 0; k < 4; ++k) pc.q.v[4 * i + k] = qn > 1.0 ? q[k] / qn : q[k];
}

#version 460
#extension GL_GOOGLE_include_directive : require
// The temporal filter of a sequence (backend_cpu/temporal_filter.cpp, backend.hpp
// temporalFilter): a one-state Kalman update of each pixel's inverse depth. The measurement
// q_m = 1 / radial (0 at +inf) with variance R = (sigmaPx / max(confidence, minConfidence))^2
// (px^2 of disparity), the prior (q_p, v_p) carried from the previous frame with P = v_p +
// processPx^2; g = |J t'| converts inverse depth into px. Where the prior has none or the
// innovation exceeds the gate, state = (q_m, R) and u, w are kept; else the gain K =
// max(P / (P + R), 1 - strength) blends them and, with strength > 0, w and u move to the
// filtered q, radial to 1 / q and points to ray / q. Elsewhere state = (-1, 0). Geometry and the update in `real`, compiled twice:
// double (-DCS_DOUBLE, the oracle's precision) and float.
#ifdef CS_DOUBLE
#extension GL_ARB_gpu_shader_fp64 : require
#endif
#include "common.glsl"
#include "camera_models.glsl"

// Mirrors VkTemporalParams<S> in backend_vulkan/kernels.cpp.
layout(buffer_reference, std430, buffer_reference_align = 8) buffer TemporalParamsRef {
  Cam cam;         // level 0's camera 0
  real tPrime[3];  // t' (triangulate's)
};

layout(push_constant) uniform PC {
  FBuf state, u, w, prior, radial, points, confidence, mask;  // state, prior, w 2 ch; points 3; confidence mask when absent
  TemporalParamsRef prm;
  int width, height, hasConfidence;
  float strength, gate, sigmaPx, processPx, minConfidence;
} pc;

// std::max(a, b): b where a < b, else a (a NaN stays).
real maxr(real a, real b) { return a < b ? b : a; }

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  pc.state.v[2 * i] = -1.0;
  pc.state.v[2 * i + 1] = 0.0;
  const float rho = pc.radial.v[i];
  if (!masked(pc.mask, pc.width, pc.height, x, y) || isnan(rho)) return;
  const Cam cam = pc.prm.cam;
  vec3r ray, J0, J1;
  vec2r px;
  if (!camUnproject(cam, vec2r(real(x), real(y)), ray) || !camProject(cam, ray, px, J0, J1)) return;
  const vec3r t = vec3r(pc.prm.tPrime[0], pc.prm.tPrime[1], pc.prm.tPrime[2]);

  const real qm = isinf(rho) ? R(0.0) : R(1.0) / real(rho);
  // Eigen's (J t').norm(): each row left to right, no fused multiply-adds.
  precise vec2r jt = vec2r((J0.x * t.x + J0.y * t.y) + J0.z * t.z, (J1.x * t.x + J1.y * t.y) + J1.z * t.z);
  precise real g = sqrt(jt.x * jt.x + jt.y * jt.y);
  const real c = maxr(real(pc.hasConfidence != 0 ? pc.confidence.v[i] : 1.0), real(pc.minConfidence));
  precise real sigma2 = real(pc.sigmaPx) * real(pc.sigmaPx);
  precise real Rm = sigma2 / (c * c);
  const real qp = real(pc.prior.v[2 * i]);
  precise real P = real(pc.prior.v[2 * i + 1]) + real(pc.processPx) * real(pc.processPx);
  precise real innovation = g * (qm - qp);
  precise real bound = real(pc.gate) * real(pc.gate) * (P + Rm);
  if (!(qp >= R(0.0)) || innovation * innovation > bound) {
    // No prior, or it disagrees: the new value at once (a moving object leaves no trail).
    pc.state.v[2 * i] = float(qm);
    pc.state.v[2 * i + 1] = float(Rm);
    return;
  }
  precise real K = maxr(P / (P + Rm), R(1.0) - real(pc.strength));
  precise real q = qp + K * (qm - qp);
  precise real v = (R(1.0) - K) * (R(1.0) - K) * P + K * K * Rm;
  pc.state.v[2 * i] = float(q);
  pc.state.v[2 * i + 1] = float(v);
  if (pc.strength == 0.0) return;  // the measurement's disparities stay
  precise vec3r moved = ray + q * t;
  vec2r there;
  if (!camProject(cam, moved, there, J0, J1)) return;
  precise real wx = there.x - real(x);
  precise real wy = there.y - real(y);
  precise real un = sqrt(wx * wx + wy * wy);
  pc.w.v[2 * i] = float(wx);
  pc.w.v[2 * i + 1] = float(wy);
  pc.u.v[i] = float(un);
  // The depth triangulate() would give from the new w, without a second pass.
  pc.radial.v[i] = q > R(0.0) ? float(R(1.0) / q) : uintBitsToFloat(0x7f800000u);
  const float nan = uintBitsToFloat(0x7fc00000u);
  pc.points.v[3 * i] = q > R(0.0) ? float(ray.x / q) : nan;
  pc.points.v[3 * i + 1] = q > R(0.0) ? float(ray.y / q) : nan;
  pc.points.v[3 * i + 2] = q > R(0.0) ? float(ray.z / q) : nan;
}

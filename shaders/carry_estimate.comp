#version 460
#extension GL_GOOGLE_include_directive : require
// A state (inverse depth q and its variance v, 2 ch) carried into the next frame's view
// (backend_cpu/carry_estimate.cpp, backend.hpp carryEstimate): a gather, each dst pixel a
// backward fixed point. T = t + extraT, ray = dstCam.unproject(x); the first q is 1 / guess(x)
// or, without a guess, src's q at the nearest pixel to srcCam.project(ray); then per step
// s = src at the nearest pixel to srcCam.project(R^T (ray - q T)), q = q_s / |R ray_s + q_s T|,
// v = v_s. (-1, 0) where x is unmasked or unprojectable, or a step finds no estimate.
// The motion (R row-major, then t) is a buffer, not a push constant: a recorded frame
// replays with each frame's motion. Geometry in `real`, compiled twice: double
// (-DCS_DOUBLE, the oracle's precision) and float.
#ifdef CS_DOUBLE
#extension GL_ARB_gpu_shader_fp64 : require
#endif
#include "common.glsl"
#include "camera_models.glsl"

// Mirrors VkCarryParams<S> in backend_vulkan/kernels.cpp.
layout(buffer_reference, std430, buffer_reference_align = 8) buffer CarryParamsRef {
  Cam srcCam;  // src's grid
  Cam dstCam;  // dst's grid
  real extraT[3];
};

layout(push_constant) uniform PC {
  FBuf dst, src, guess, motion, mask;  // dst, src 2 ch; guess (mask when absent), mask 1 ch on dst's grid
  CarryParamsRef prm;
  int width, height;        // dst's
  int srcWidth, srcHeight;  // src's
  int iterations, hasGuess;
} pc;

// The state at the src pixel nearest to the projection of direction d (floor(c + 0.5 -
// kCarryTie) in `real`, as the oracle in double: halfway positions go to the lower pixel): false where d does not project, the pixel lies outside
// src, holds no estimate (q < 0) or does not unproject.
bool lookUp(Cam cam, vec3r d, out float q, out float v, out vec3r ray) {
  q = -1.0;
  v = 0.0;
  ray = vec3r(0);
  vec2r px;
  vec3r J0, J1;
  if (!camProject(cam, d, px, J0, J1)) return false;
  const real kHalf = D(0.499LF, 0.499);  // 0.5 - kCarryTie (backend.hpp)
  precise real cx = px.x + kHalf;
  precise real cy = px.y + kHalf;
  const real nx = floor(cx), ny = floor(cy);
  if (!(nx >= R(0.0) && ny >= R(0.0) && nx < real(pc.srcWidth) && ny < real(pc.srcHeight))) return false;
  const int ix = int(nx), iy = int(ny);
  const int i = iy * pc.srcWidth + ix;
  q = pc.src.v[2 * i];
  v = pc.src.v[2 * i + 1];
  return q >= 0.0 && camUnproject(cam, vec2r(real(ix), real(iy)), ray);
}

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  pc.dst.v[2 * i] = -1.0;
  pc.dst.v[2 * i + 1] = 0.0;
  if (!masked(pc.mask, pc.width, pc.height, x, y)) return;
  const Cam srcCam = pc.prm.srcCam, dstCam = pc.prm.dstCam;
  vec3r ray;
  if (!camUnproject(dstCam, vec2r(real(x), real(y)), ray)) return;
  // The motion's floats, widened as the oracle's Eigen::Matrix3d and Vector3d take them.
  real Rm[9];
  for (int k = 0; k < 9; ++k) Rm[k] = real(pc.motion.v[k]);
  precise vec3r T = vec3r(real(pc.motion.v[9]) + pc.prm.extraT[0], real(pc.motion.v[10]) + pc.prm.extraT[1],
                          real(pc.motion.v[11]) + pc.prm.extraT[2]);

  real q;
  float sq, sv;
  vec3r sray;
  if (pc.hasGuess != 0) {
    const float radial = pc.guess.v[i];
    if (isnan(radial) || !(radial > 0.0)) return;  // NaN or <= 0: no guess
    q = isinf(radial) ? R(0.0) : R(1.0) / real(radial);
  } else {
    if (!lookUp(srcCam, ray, sq, sv, sray)) return;
    q = real(sq);
  }
  bool found = false;
  for (int k = 0; k < pc.iterations; ++k) {
    // R^T (ray - q T) and R ray_s + q_s T as Eigen (3.4, SSE2) evaluates them, no fused
    // multiply-adds (as backend_cuda/carry_estimate.cu): R^T's rows summed first to last; R's
    // first two rows first to last (one packet), the third from the last pair (its scalar
    // tail); the norm first to last.
    precise vec3r m = ray - q * T;
    precise vec3r d = vec3r((Rm[0] * m.x + Rm[3] * m.y) + Rm[6] * m.z, (Rm[1] * m.x + Rm[4] * m.y) + Rm[7] * m.z,
                            (Rm[2] * m.x + Rm[5] * m.y) + Rm[8] * m.z);
    found = lookUp(srcCam, d, sq, sv, sray);
    if (!found) break;
    const real qs = real(sq);
    precise vec3r back = vec3r((Rm[0] * sray.x + Rm[1] * sray.y) + Rm[2] * sray.z,
                               (Rm[3] * sray.x + Rm[4] * sray.y) + Rm[5] * sray.z,
                               Rm[6] * sray.x + (Rm[7] * sray.y + Rm[8] * sray.z)) +
                         qs * T;
    precise real n = sqrt(back.x * back.x + back.y * back.y + back.z * back.z);
    q = qs / n;
  }
  if (!found) return;
  pc.dst.v[2 * i] = float(q);
  pc.dst.v[2 * i + 1] = sv;
}

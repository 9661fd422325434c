#version 460
#extension GL_GOOGLE_include_directive : require
// The host's planes written into level 0's estimate (backend_cpu/plain_fill.cpp
// fillPlanes, backend.hpp): where the coarse pixel's label l >= 0, q = a . ray with a the
// l-th plane, and where q >= 0 and ray + q t' projects, w = pi(ray + q t') - x, u = |w| and
// planeConfidence the label's confidence (0 elsewhere).
#ifdef CS_DOUBLE
#extension GL_ARB_gpu_shader_fp64 : require
#endif
#include "common.glsl"
#include "camera_models.glsl"

// Mirrors VkTriangulateParams<S> in backend_vulkan/kernels.cpp (the same block).
layout(buffer_reference, std430, buffer_reference_align = 8) buffer FillPlanesParamsRef {
  Cam cam0;
  real tPrime[3];
};

layout(push_constant) uniform PC {
  FBuf u, w, planeConfidence, labels, planes, mask;
  FillPlanesParamsRef prm;
  int width, height, labelWidth, labelHeight, planeValues;
} pc;

int coarseOf(int X, int coarse, int full) { return ((2 * X + 1) * coarse) / (2 * full); }

void main() {
  const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  pc.planeConfidence.v[i] = 0.0;
  if (!masked(pc.mask, pc.width, pc.height, x, y)) return;
  const int lx = coarseOf(x, pc.labelWidth, pc.width), ly = coarseOf(y, pc.labelHeight, pc.height);
  const float label = pc.labels.v[2 * (ly * pc.labelWidth + lx)];
  if (!(label >= 0.0) || int(label) >= pc.planeValues / 3) return;
  const int k = 3 * int(label);
  Cam cam = pc.prm.cam0;
  vec3r ray;
  if (!camUnproject(cam, vec2r(real(x), real(y)), ray)) return;
  const real q = real(pc.planes.v[k]) * ray.x + real(pc.planes.v[k + 1]) * ray.y + real(pc.planes.v[k + 2]) * ray.z;
  vec2r px;
  vec3r J0, J1;
  const vec3r t = vec3r(pc.prm.tPrime[0], pc.prm.tPrime[1], pc.prm.tPrime[2]);
  if (!(q >= R(0.0)) || !camProject(cam, ray + q * t, px, J0, J1)) return;
  const real wx = px.x - real(x), wy = px.y - real(y);
  pc.w.v[2 * i] = float(wx);
  pc.w.v[2 * i + 1] = float(wy);
  pc.u.v[i] = float(sqrt(wx * wx + wy * wy));
  pc.planeConfidence.v[i] = pc.labels.v[2 * (ly * pc.labelWidth + lx) + 1];
}

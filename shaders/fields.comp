#version 460
#extension GL_GOOGLE_include_directive : require
// Per rig / per pose: valid mask, calibration field c(x) = pi1(R pi0^-1(x)) - x and the
// trajectory field T(x) = normalize(J_pi0(pi0^-1(x)) t') (core/src/fields.cpp
// fieldsAtPixel, backend_cpu/fields.cpp). Compiled twice: double (-DCS_DOUBLE) and float.
#ifdef CS_DOUBLE
#extension GL_ARB_gpu_shader_fp64 : require
#endif
#include "common.glsl"
#include "camera_models.glsl"

// Mirrors VkFieldsParams<S> in backend_vulkan/vulkan_backend.cpp.
layout(buffer_reference, std430, buffer_reference_align = 8) buffer FieldsParamsRef {
  Cam cam0, cam1;
  real R[9];        // row-major, X1 = R X0 + t
  real tPrime[3];   // R^T t
  real tDir[3];     // tPrime / |tPrime|
  real halfFov;     // 0.5 maxFovDeg in radians; only used when useFov != 0
  real epipole;     // epipoleDeg in radians
  int useFov;
};

layout(push_constant) uniform PC {
  FBuf mask, calibration, trajectory;
  FieldsParamsRef prm;
  int w, h;
} pc;

// The ray lies farther than halfFov from its camera's optical axis (z); off without a limit.
bool beyondFov(vec3r ray) {
  return pc.prm.useFov != 0 && atan2r(sqrt(ray.x * ray.x + ray.y * ray.y), ray.z) > pc.prm.halfFov;
}

bool fieldsAt(int x, int y, out vec2 calibration, out vec2 trajectory) {
  calibration = vec2(0.0);
  trajectory = vec2(0.0);
  Cam cam0 = pc.prm.cam0;
  vec2r px = vec2r(real(x), real(y));
  vec3r ray;
  if (!camUnproject(cam0, px, ray)) return false;
  if (beyondFov(ray)) return false;
  vec3r tDir = vec3r(pc.prm.tDir[0], pc.prm.tDir[1], pc.prm.tDir[2]);
  real cosB = abs(ray.x * tDir.x + ray.y * tDir.y + ray.z * tDir.z);
  if (acosr(min(R(1.0), cosB)) < pc.prm.epipole) return false;

  Cam cam1 = pc.prm.cam1;
  vec3r r1 = vec3r(pc.prm.R[0] * ray.x + pc.prm.R[1] * ray.y + pc.prm.R[2] * ray.z,
                   pc.prm.R[3] * ray.x + pc.prm.R[4] * ray.y + pc.prm.R[5] * ray.z,
                   pc.prm.R[6] * ray.x + pc.prm.R[7] * ray.y + pc.prm.R[8] * ray.z);
  if (beyondFov(r1)) return false;  // camera 1's field of view too
  vec2r px1;
  vec3r J0, J1;
  if (!camProject(cam1, r1, px1, J0, J1) || !camInImage(cam1, px1)) return false;

  vec2r proj;
  if (!camProject(cam0, ray, proj, J0, J1)) return false;
  vec3r tp = vec3r(pc.prm.tPrime[0], pc.prm.tPrime[1], pc.prm.tPrime[2]);
  vec2r tangent = vec2r(J0.x * tp.x + J0.y * tp.y + J0.z * tp.z, J1.x * tp.x + J1.y * tp.y + J1.z * tp.z);
  real n = sqrt(tangent.x * tangent.x + tangent.y * tangent.y);
  if (!(n > D(1e-12LF, 1e-12))) return false;
  tangent /= n;
  calibration = vec2(float(px1.x - px.x), float(px1.y - px.y));
  trajectory = vec2(float(tangent.x), float(tangent.y));
  return true;
}

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.w || y >= pc.h) return;
  const int i = y * pc.w + x;
  vec2 calibration, trajectory;
  bool valid = fieldsAt(x, y, calibration, trajectory);
  if (!valid) {
    calibration = vec2(0.0);
    trajectory = vec2(0.0);
  }
  pc.mask.v[i] = valid && pc.mask.v[i] != 0.0 ? 1.0 : 0.0;
  pc.calibration.v[2 * i] = calibration.x;
  pc.calibration.v[2 * i + 1] = calibration.y;
  pc.trajectory.v[2 * i] = trajectory.x;
  pc.trajectory.v[2 * i + 1] = trajectory.y;
}

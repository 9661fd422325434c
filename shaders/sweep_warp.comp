#version 460
#extension GL_GOOGLE_include_directive : require
// The plane-sweep volume (backend_cpu/plane_sweep.cpp sweepWarp): for every masked pixel
// and every hypothesis k, `image` sampled bilinearly where the pixel's ray meets the
// sphere of inverse depth q_k; -1 where the pixel is not masked, its ray does not exist or
// x_k is not a valid projection inside the image. Geometry in `real`, compiled twice:
// double (-DCS_DOUBLE) and float.
#ifdef CS_DOUBLE
#extension GL_ARB_gpu_shader_fp64 : require
#endif
#include "common.glsl"
#include "plane_sweep.glsl"
#include "sampling.glsl"

const float kNoSample = -1.0;

layout(push_constant) uniform PC {
  FBuf volume, image, mask;  // volume: `planes` channels; image, mask: 1 channel
  SweepParamsRef prm;
  int width, height, planes;
} pc;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const Cam cam = pc.prm.cam;
  const vec3r t = sweepTranslation(pc.prm);
  const real qMax = pc.prm.qMax;
  vec3r ray;
  const bool seen = masked(pc.mask, pc.width, pc.height, x, y) && camUnproject(cam, vec2r(real(x), real(y)), ray);
  for (int k = 0; k < pc.planes; ++k) {
    float value = kNoSample;
    vec2r px;
    if (seen && projectHypothesis(cam, ray, t, planeInverseDepth(qMax, pc.planes, real(k)), px))
      value = sampleBilinear(pc.image, pc.width, pc.height, 1, 0, float(px.x), float(px.y));
    pc.volume.v[idx(pc.width, pc.planes, x, y, k)] = value;
  }
}

#version 460
#extension GL_GOOGLE_include_directive : require
// The plane-sweep volume (backend_cpu/plane_sweep.cpp sweepWarp): for every masked pixel
// and every hypothesis k, `image` sampled bilinearly where the pixel's ray meets the
// sphere of inverse depth q_k; -1 where the pixel is not masked, its ray does not exist or
// x_k is not a valid projection inside the image. Geometry in `real`, compiled twice:
// double (-DCS_DOUBLE) and float.
// A work group takes kPixels adjacent pixels of a row: their rays first (one invocation
// each, into shared memory), then its kGroupSize invocations over the pixels' planes, which
// form one contiguous run of the interleaved volume (consecutive invocations write
// consecutive floats), as backend_cuda/plane_sweep.cu.
#ifdef CS_DOUBLE
#extension GL_ARB_gpu_shader_fp64 : require
#endif
#define CS_OWN_WORK_GROUP
#include "common.glsl"
#include "plane_sweep.glsl"
#include "sampling.glsl"

const int kPixels = 32;      // mirrors kSweepWarpPixels in backend_vulkan/kernels.cpp
const int kGroupSize = 256;
layout(local_size_x = kGroupSize, local_size_y = 1, local_size_z = 1) in;

const float kNoSample = -1.0;

layout(push_constant) uniform PC {
  FBuf volume, image, mask;  // volume: `planes` channels; image, mask: 1 channel
  SweepParamsRef prm;
  int width, height, planes;
} pc;

shared vec3r rays[kPixels];
shared bool usable[kPixels];

void main() {
  const int lid = int(gl_LocalInvocationIndex);
  const int x0 = int(gl_WorkGroupID.x) * kPixels, y = int(gl_WorkGroupID.y);
  const int count = min(kPixels, pc.width - x0);
  const Cam cam = pc.prm.cam;
  if (lid < count) {
    const int x = x0 + lid;
    vec3r ray = vec3r(0.0);
    usable[lid] = masked(pc.mask, pc.width, pc.height, x, y) && camUnproject(cam, vec2r(real(x), real(y)), ray);
    rays[lid] = ray;
  }
  barrier();
  const vec3r t = sweepTranslation(pc.prm);
  const real qMax = pc.prm.qMax;
  const int base = idx(pc.width, pc.planes, x0, y, 0);
  for (int i = lid; i < count * pc.planes; i += kGroupSize) {
    const int pixel = i / pc.planes, k = i % pc.planes;
    float value = kNoSample;
    vec2r px;
    if (usable[pixel] && projectHypothesis(cam, rays[pixel], t, planeInverseDepth(qMax, pc.planes, real(k)), px))
      value = sampleBilinear(pc.image, pc.width, pc.height, 1, 0, float(px.x), float(px.y));
    pc.volume.v[base + i] = value;
  }
}

#version 460
#extension GL_GOOGLE_include_directive : require
// The band sweep's volume (backend_cpu/plane_sweep.cpp sweepBandWarp): each masked pixel's
// band from the coarse sweep's answer (bandFirst; -1 where the pixel is not masked or its
// coarse pixel found nothing), and channel k of the volume the image sampled as
// sweep_warp.comp samples hypothesis first + k; -1 where it cannot be sampled. Geometry in
// `real`, compiled twice: double (-DCS_DOUBLE) and float.
// As sweep_warp.comp, a work group takes kPixels adjacent pixels of a row: their rays and
// bands first (one invocation each, into shared memory), then its kGroupSize invocations
// over the pixels' band channels, one contiguous run of the interleaved volume.
#ifdef CS_DOUBLE
#extension GL_ARB_gpu_shader_fp64 : require
#endif
#define CS_OWN_WORK_GROUP
#include "common.glsl"
#include "plane_sweep.glsl"
#include "sampling.glsl"

const int kPixels = 32;  // mirrors kSweepBandWarpPixels in backend_vulkan/kernels.cpp
const int kGroupSize = 256;
const int kBandMargin = 2;  // mirrors kBandMargin in core/internal/curvestereo/backend.hpp
layout(local_size_x = kGroupSize, local_size_y = 1, local_size_z = 1) in;

const float kNoSample = -1.0;

layout(push_constant) uniform PC {
  FBuf volume, first, image, coarseBest, mask;  // volume: `band` channels; coarseBest: 2
  SweepParamsRef prm;
  int width, height, planes, band;
  int coarseWidth, coarseHeight;
  float coarseScale;  // coarse / fine
} pc;

shared vec3r rays[kPixels];
shared bool usable[kPixels];
shared int firsts[kPixels];

// A coarse winner as a plane index in the oracle's arithmetic (`real` for its double),
// rounded half up; -1 for none.
int coarsePlane(int cx, int cy) {
  const float q = pc.coarseBest.v[idx(pc.coarseWidth, 2, cx, cy, 0)];
  if (q < 0.0) return -1;
  precise real n = real(q) * real(pc.planes - 1) / pc.prm.qMax + real(0.5);
  return int(floor(n));
}

// The pixel's first hypothesis: the coarse pixel in float, the band centred on the coarse
// 3x3 neighbourhood's winners where they fit with kBandMargin to spare, else on the
// nearest coarse pixel's. -1 where it has none.
int bandFirst(int x, int y) {
  if (!masked(pc.mask, pc.width, pc.height, x, y)) return -1;
  precise float fx = (float(x) + 0.5) * pc.coarseScale, fy = (float(y) + 0.5) * pc.coarseScale;
  const int cx = min(pc.coarseWidth - 1, int(fx)), cy = min(pc.coarseHeight - 1, int(fy));
  const int nearest = coarsePlane(cx, cy);
  if (nearest < 0) return -1;
  int lo = nearest, hi = nearest;
  for (int ny = max(cy - 1, 0); ny <= min(cy + 1, pc.coarseHeight - 1); ++ny)
    for (int nx = max(cx - 1, 0); nx <= min(cx + 1, pc.coarseWidth - 1); ++nx) {
      const int n = coarsePlane(nx, ny);
      if (n >= 0) lo = min(lo, n), hi = max(hi, n);
    }
  const int centre = hi - lo + 2 * kBandMargin <= pc.band ? (lo + hi + 1) / 2 : nearest;
  return min(max(centre - pc.band / 2, 0), pc.planes - pc.band);
}

void main() {
  const int lid = int(gl_LocalInvocationIndex);
  const int x0 = int(gl_WorkGroupID.x) * kPixels, y = int(gl_WorkGroupID.y);
  const int count = min(kPixels, pc.width - x0);
  const Cam cam = pc.prm.cam;
  if (lid < count) {
    const int x = x0 + lid;
    const int start = bandFirst(x, y);
    // The oracle places the band before it unprojects: a pixel without a ray keeps its
    // band, with every sample -1.
    vec3r ray = vec3r(0.0);
    usable[lid] = start >= 0 && camUnproject(cam, vec2r(real(x), real(y)), ray);
    rays[lid] = ray;
    firsts[lid] = start;
    pc.first.v[y * pc.width + x] = float(start);
  }
  barrier();
  const vec3r t = sweepTranslation(pc.prm);
  const real qMax = pc.prm.qMax;
  const int base = idx(pc.width, pc.band, x0, y, 0);
  for (int i = lid; i < count * pc.band; i += kGroupSize) {
    const int pixel = i / pc.band, k = i % pc.band;
    float value = kNoSample;
    vec2r px;
    if (usable[pixel] &&
        projectHypothesis(cam, rays[pixel], t, planeInverseDepth(qMax, pc.planes, real(firsts[pixel] + k)), px))
      value = sampleBilinear(pc.image, pc.width, pc.height, 1, 0, float(px.x), float(px.y));
    pc.volume.v[base + i] = value;
  }
}

// Shared by the plane-sweep shaders that do geometry (sweep_warp, sweep_band_warp,
// sweep_initialise) or refine winners into inverse depths (sweep_select,
// sweep_band_select): the sweep's parameter block, where a hypothesis lands and the
// parabola's refinement (backend_cpu/plane_sweep.cpp).
#ifndef CS_PLANE_SWEEP_GLSL
#define CS_PLANE_SWEEP_GLSL
#include "camera_models.glsl"

// Mirrors VkSweepParams<S> in backend_vulkan/vulkan_backend.cpp.
layout(buffer_reference, std430, buffer_reference_align = 8) buffer SweepParamsRef {
  Cam cam;    // the level's camera
  real t[3];  // the other view's centre as seen from the reference: X -> X + t
  real qMax;  // inverse depth of the nearest sphere
};

vec3r sweepTranslation(SweepParamsRef prm) { return vec3r(prm.t[0], prm.t[1], prm.t[2]); }

const float kNoCost = 2.0;  // cost where nothing scored (the worst 1 - ZNCC)
const float kPaths = 4.0;   // scanline directions summed in `aggregated`

// Vertex of the parabola through (-1, before), (0, winner), (1, after), within half a
// plane; 0 where a neighbour did not score or the costs do not curve upwards.
float parabolaOffset(float before, float winner, float after) {
  if (before >= kNoCost || after >= kNoCost) return 0.0;
  precise float curvature = before - 2.0 * winner + after;
  if (!(curvature > 1e-6)) return 0.0;
  precise float offset = 0.5 * (before - after) / curvature;
  return min(0.5, max(-0.5, offset));
}

// Inverse depth of hypothesis k (fractional after the parabola refinement).
real planeInverseDepth(real qMax, int planes, real k) { return qMax * k / real(planes - 1); }

// Where the reference ray, on the sphere of inverse depth q, lands in the other view;
// false where it does not project or lands outside the image.
bool projectHypothesis(Cam cam, vec3r ray, vec3r t, real q, out vec2r px) {
  // The oracle adds q t to the ray without fused multiply-adds.
  precise vec3r moved = ray + q * t;
  vec3r J0, J1;
  return camProject(cam, moved, px, J0, J1) && camInImage(cam, px);
}

#endif

// Shared by the plane-sweep shaders that do geometry (sweep_warp, sweep_initialise) or turn
// plane indices into inverse depths (sweep_select): the sweep's parameter block and where
// a hypothesis lands (backend_cpu/plane_sweep.cpp).
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

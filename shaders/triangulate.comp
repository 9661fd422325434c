#version 460
#extension GL_GOOGLE_include_directive : require
// Radial depth and 3-D points from the warp (core/src/triangulate.cpp triangulateRadial,
// backend_cpu/triangulate.cpp): NaN outside the mask or where x or x + w do not unproject,
// +inf (points NaN) where the rays do not converge in front of both cameras.
#ifdef CS_DOUBLE
#extension GL_ARB_gpu_shader_fp64 : require
#endif
#include "common.glsl"
#include "camera_models.glsl"

// Mirrors VkTriangulateParams<S> in backend_vulkan/vulkan_backend.cpp.
layout(buffer_reference, std430, buffer_reference_align = 8) buffer TriangulateParamsRef {
  Cam cam0;
  real tPrime[3];
};

layout(push_constant) uniform PC {
  FBuf radial, points, w, mask;
  TriangulateParamsRef prm;
  int width, height;
} pc;

// Each output written once: the radial depth r and the point (NaN where none).
void store(int i, float r, vec3 point) {
  pc.radial.v[i] = r;
  pc.points.v[3 * i] = point.x;
  pc.points.v[3 * i + 1] = point.y;
  pc.points.v[3 * i + 2] = point.z;
}

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  const float nan = quietNaN();
  const vec3 none = vec3(nan);
  if (!masked(pc.mask, pc.width, pc.height, x, y)) {
    store(i, nan, none);
    return;
  }

  Cam cam0 = pc.prm.cam0;
  vec2r px = vec2r(real(x), real(y));
  vec2r wx = vec2r(real(pc.w.v[2 * i]), real(pc.w.v[2 * i + 1]));
  vec3r d0, d1;
  if (!camUnproject(cam0, px, d0) || !camUnproject(cam0, px + wx, d1)) {
    store(i, nan, none);
    return;
  }
  vec3r c1 = -vec3r(pc.prm.tPrime[0], pc.prm.tPrime[1], pc.prm.tPrime[2]);
  vec3r n = cross(d0, d1);
  real n2 = n.x * n.x + n.y * n.y + n.z * n.z;
  bool infinite = n2 < D(1e-24LF, 1e-24);
  real a = R(0.0);
  if (!infinite) {
    vec3r cd1 = cross(c1, d1), cd0 = cross(c1, d0);
    a = (cd1.x * n.x + cd1.y * n.y + cd1.z * n.z) / n2;
    real b = (cd0.x * n.x + cd0.y * n.y + cd0.z * n.z) / n2;
    infinite = !(a > R(0.0)) || !(b > R(0.0));
  }
  if (infinite) {
    store(i, posInf(), none);
    return;
  }
  store(i, float(a), vec3(float(a * d0.x), float(a * d0.y), float(a * d0.z)));
}

#version 460
#extension GL_GOOGLE_include_directive : require
// Each camera pixel placed in the rig's equirectangular panorama (backend_cpu/panorama.cpp
// panoramaPlace, backend.hpp): its column, row, footprint half-sizes and range, from its
// own and its four neighbours' placements. All in float, as the oracle.
#include "common.glsl"
#include "real.glsl"

layout(push_constant) uniform PC {
  FBuf place, radial, rays;
  int width, height;  // the camera's grid
  int panoWidth;      // W; the panorama's rows W / 2
  float cx, cy, cz;   // the camera's centre in the panorama's frame
  float agreement, maxSplat;  // kPanoramaAgreement, kPanoramaMaxSplat
  float parallaxSlack;
} pc;


// atan2 with both signs, signed zeros as the oracle's (the seam: -0 and +0 at longitude
// -pi and +pi), within a few ulp (real.glsl atan2r).
float atan2Signed(float y, float x) {
  const float t = atan2r(abs(y), x);
  return floatBitsToInt(y) < 0 ? -t : t;
}

// cos of a latitude (|l| <= pi/2) within an ulp (as the oracle's cosf; device cos may be
// off by 2^-11, and real.glsl's float reduction by pi/2 by 4e-8, much of cos near the
// poles): Taylor series of cos about 0 below pi/4, of sin(pi/2 - |l|) above. The leading
// term's rounding error is carried into the small ones.
float cosLatitude(float l) {
  const float a = abs(l);
  if (a <= 0.78539816) {
    precise float a2 = a * a;
    precise float h = 0.5 * a2;
    precise float lead = 1.0 - h;
    precise float rest = ((1.0 - lead) - h) +
                         a2 * a2 * (4.16666667e-2 + a2 * (-1.38888889e-3 + a2 * (2.48015873e-5 + a2 * -2.75573192e-7)));
    precise float c = lead + rest;
    return c;
  }
  // sin(pi/2 - a): float(pi/2) - a is exact (a >= pi/4); pi/2's remainder joins the small terms.
  const float lo = -4.37113883e-8;
  precise float rh = 1.57079637 - a;
  precise float r = rh + lo;
  precise float r2 = r * r;
  precise float s =
      rh + (lo + r * r2 * (-1.66666667e-1 + r2 * (8.33333333e-3 + r2 * (-1.98412698e-4 + r2 * 2.75573192e-6))));
  return s;
}

bool hasRay(int i) {
  const vec3 d = vec3(pc.rays.v[3 * i], pc.rays.v[3 * i + 1], pc.rays.v[3 * i + 2]);
  return !any(isnan(d)) && !any(isinf(d));
}

// (column, row, range) of pixel i with radial r (not NaN) and a finite ray.
vec3 placed(int i, float r) {
  const vec3 d = vec3(pc.rays.v[3 * i], pc.rays.v[3 * i + 1], pc.rays.v[3 * i + 2]);
  const bool infinite = isinf(r);  // as the oracle: either infinity is the direction
  precise vec3 P = infinite ? d : r * d + vec3(pc.cx, pc.cy, pc.cz);
  precise float horizontal = sqrt(P.x * P.x + P.z * P.z);
  precise float norm = sqrt(P.x * P.x + P.y * P.y + P.z * P.z);
  const float lon = atan2Signed(P.x, P.z), lat = atan2Signed(-P.y, horizontal);
  const float W = float(pc.panoWidth), H = float(pc.panoWidth / 2);
  precise float column = (lon + PI_R) / (2.0 * PI_R) * W - 0.5;
  precise float row = (PI_R / 2.0 - lat) / PI_R * H - 0.5;
  return vec3(column, row, infinite ? posInf() : norm);
}

void main() {
  const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  const float r = pc.radial.v[i];
  if (isnan(r) || !hasRay(i)) {
    for (int k = 0; k < 5; ++k) pc.place.v[5 * i + k] = quietNaN();
    return;
  }
  const vec3 own = placed(i, r);
  const float W = float(pc.panoWidth), H = float(pc.panoWidth / 2);
  // a: the largest steps to the row's neighbours, b: to the column's (the oracle's order).
  vec2 a = vec2(0.0), b = vec2(0.0);
  const ivec2 offsets[4] = ivec2[4](ivec2(1, 0), ivec2(0, 1), ivec2(-1, 0), ivec2(0, -1));
  for (int k = 0; k < 4; ++k) {
    const int nx = x + offsets[k].x, ny = y + offsets[k].y;
    if (!insideGrid(pc.width, pc.height, nx, ny)) continue;
    const int j = ny * pc.width + nx;
    const float rn = pc.radial.v[j];
    if (isnan(rn) || !hasRay(j)) continue;
    precise float qn = 1.0 / rn, q = 1.0 / r;
    precise float gap = abs(qn - q);
    precise float tolerance = pc.agreement * max(qn, q) + pc.parallaxSlack;
    if (!(gap <= tolerance)) continue;
    precise vec2 step = placed(j, rn).xy - own.xy;
    // Across the seam: W / 2 < |step.x| <= W (columns lie in [-0.5, W - 0.5]), where
    // remainder(step.x, W) is step.x -+ W, exact in float; step.x - W roundEven(step.x / W)
    // would keep step.x where the division rounds to exactly 0.5.
    if (abs(step.x) > W / 2.0) step.x -= step.x > 0.0 ? W : -W;
    if (offsets[k].y == 0)
      a = vec2(max(a.x, abs(step.x)), max(a.y, abs(step.y)));
    else
      b = vec2(max(b.x, abs(step.x)), max(b.y, abs(step.y)));
  }
  precise vec2 s = a + b;
  precise float l = PI_R / 2.0 - PI_R * (own.y + 0.5) / H;
  precise float widest = pc.maxSplat / max(cosLatitude(l), 2.0 * pc.maxSplat / W);
  precise float hx = clamp(s.x / 2.0, 0.5, widest);
  precise float hy = clamp(s.y / 2.0, 0.5, pc.maxSplat);
  pc.place.v[5 * i] = own.x;
  pc.place.v[5 * i + 1] = own.y;
  pc.place.v[5 * i + 2] = hx;
  pc.place.v[5 * i + 3] = hy;
  pc.place.v[5 * i + 4] = own.z;
}

#version 460
#extension GL_GOOGLE_include_directive : require
// Per warp: the tangent g = normalize(T(x + w)) and the linearised data term at x + w
// (backend_cpu/warp_derivatives.cpp).
// With -DCS_WARP_TAIL (the fused tail of a warp, Backend::warpTail): first the pixel's
// accumulate (backend_cpu/accumulate.cpp) from uIn (the median of u, or u itself), then,
// with `derive`, the next warp's derivatives from the accumulated u and w. Every step works
// on the pixel's own u, w and tangent, so one invocation does them in the fine kernels' order.
#include "sampling.glsl"

layout(push_constant) uniform PC {
  FBuf u0, iu, iz, tangent, i0, i1, trajectory, w, u, mask, confidence;
  int width, height, hasConfidence;
  float weightFloor;
#ifdef CS_WARP_TAIL
  FBuf uIn;
  float duMax;
  int derive;
#endif
} pc;

float derivativeAlong(FBuf image, float x, float y, float gx, float gy) {
  float fp2 = sampleBilinear(image, pc.width, pc.height, 1, 0, x + 2.0 * gx, y + 2.0 * gy);
  float fp1 = sampleBilinear(image, pc.width, pc.height, 1, 0, x + 1.0 * gx, y + 1.0 * gy);
  float fm1 = sampleBilinear(image, pc.width, pc.height, 1, 0, x + -1.0 * gx, y + -1.0 * gy);
  float fm2 = sampleBilinear(image, pc.width, pc.height, 1, 0, x + -2.0 * gx, y + -2.0 * gy);
  return (-fp2 + 8.0 * fp1 - 8.0 * fm1 + fm2) / 12.0;
}

bool sampleable(float x, float y, float gx, float gy) {
  const float reach = 2.0;
  for (int k = 0; k < 2; ++k) {
    float s = k == 0 ? -reach : reach;
    float sx = x + s * gx, sy = y + s * gy;
    if (sx < 0.0 || sy < 0.0 || sx > float(pc.width - 1) || sy > float(pc.height - 1)) return false;
  }
  return masked(pc.mask, pc.width, pc.height, lroundf(x), lroundf(y));
}

// The derivatives of pixel (x, y) at index i, whose u and w are given.
void derivatives(int x, int y, int i, bool inMask, float u, vec2 w) {
  pc.u0.v[i] = u;
  pc.iu.v[i] = 0.0;
  pc.iz.v[i] = 0.0;
  pc.tangent.v[2 * i] = 0.0;
  pc.tangent.v[2 * i + 1] = 0.0;
  if (!inMask) return;

  const float px = float(x) + w.x, py = float(y) + w.y;
  float gx = sampleBilinear(pc.trajectory, pc.width, pc.height, 2, 0, px, py);
  float gy = sampleBilinear(pc.trajectory, pc.width, pc.height, 2, 1, px, py);
  float n = sqrt(gx * gx + gy * gy);
  if (n < 1e-3) {  // interpolated across a flip of the field: keep the pixel's own tangent
    gx = pc.trajectory.v[2 * i];
    gy = pc.trajectory.v[2 * i + 1];
    n = sqrt(gx * gx + gy * gy);
  }
  gx /= n;
  gy /= n;
  pc.tangent.v[2 * i] = gx;
  pc.tangent.v[2 * i + 1] = gy;
  if (!sampleable(px, py, gx, gy)) return;

  // Confidence-weighted data term: lambda c |rho| = lambda |c rho|.
  const float weight = pc.hasConfidence != 0 ? max(pc.confidence.v[i], pc.weightFloor) : 1.0;
  pc.iz.v[i] = weight * (sampleBilinear(pc.i1, pc.width, pc.height, 1, 0, px, py) - pc.i0.v[i]);
  pc.iu.v[i] =
      weight * 0.5 * (derivativeAlong(pc.i1, px, py, gx, gy) + derivativeAlong(pc.i0, float(x), float(y), gx, gy));
}

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  const bool inMask = masked(pc.mask, pc.width, pc.height, x, y);
#ifdef CS_WARP_TAIL
  // du = clamp(u - u0, +-duMax); u = u0 + du; w += du * tangent at masked pixels.
  float u = pc.uIn.v[i];
  vec2 w = vec2(pc.w.v[2 * i], pc.w.v[2 * i + 1]);
  if (inMask) {
    const float u0 = pc.u0.v[i];
    const float du = min(max(u - u0, -pc.duMax), pc.duMax);
    u = u0 + du;
    w.x += du * pc.tangent.v[2 * i];
    w.y += du * pc.tangent.v[2 * i + 1];
    pc.w.v[2 * i] = w.x;
    pc.w.v[2 * i + 1] = w.y;
  }
  pc.u.v[i] = u;
  if (pc.derive != 0) derivatives(x, y, i, inMask, u, w);
#else
  derivatives(x, y, i, inMask, pc.u.v[i], vec2(pc.w.v[2 * i], pc.w.v[2 * i + 1]));
#endif
}

#version 460
#extension GL_GOOGLE_include_directive : require
// The initial state from two sweeps (backend_cpu/plane_sweep.cpp sweepInitialise): the
// reference hypothesis q gives x_q; the other view's hypothesis at the nearest pixel to
// x_q carries it back, and the round-trip error e gives confidence = exp(-(e / tol)^2)
// (0 where the reference has no hypothesis, the round trip fails or mask is 0). Where
// confidence >= acceptConfidence the sweep's w = x_q - x and u = |w| replace the
// coarse-to-fine estimate (u, w in/out); elsewhere they are left as they are (pass 0).
// Pass 1, a second dispatch over pass 0's confidence: an inconsistent pixel whose round
// trip could be made looks for occlusion (occludedSurface in the oracle) and may take the
// inverse depth of the consistent surface ahead of it.
// Geometry in `real`, compiled twice: double (-DCS_DOUBLE) and float.
#ifdef CS_DOUBLE
#extension GL_ARB_gpu_shader_fp64 : require
#endif
#include "common.glsl"
#include "plane_sweep.glsl"

layout(push_constant) uniform PC {
  FBuf u, w, confidence, best, other, mask;  // w, best, other: 2 channels
  SweepParamsRef prm;  // t: the reference sweep's translation (`other` was swept with -t)
  int width, height;
  float tolerancePx, acceptConfidence, maxCost;
  int pass;    // 0: confidence and consistent pixels; 1: occlusions (after pass 0)
  int planes;  // pass 1's reach in steps each way
} pc;

// std::lround of a real (halves away from zero): the oracle rounds x_q in double, and
// rounding float(x_q) instead could pick another pixel.
int lroundr(real v) {
  real a = abs(v);
  real r = floor(a);
  if (a - r >= R(0.5)) r += R(1.0);
  return int(v < R(0.0) ? -r : r);
}

// exp(x), x <= 0. The oracle takes exp in double and rounds to float; GLSL's exp is float
// only (and a few ulps off), and a confidence an ulp off could cross acceptConfidence. So
// with doubles: x = n ln2 + r, |r| <= ln2 / 2, and exp(r) by its Taylor series in nested
// form (16 terms: the first one left out is below 1e-22).
real expNonPositive(real x) {
#ifdef CS_DOUBLE
  if (x < -745.0LF) return 0.0LF;  // below the smallest double
  const double kLn2Hi = 6.93147180369123816490e-01LF, kLn2Lo = 1.90821492927058770002e-10LF;
  const double n = floor(x * 1.44269504088896340736LF + 0.5LF);
  precise double r = (x - n * kLn2Hi) - n * kLn2Lo;
  precise double s = 1.0LF;
  for (int i = 16; i >= 1; --i) s = 1.0LF + s * r / double(i);
  return ldexp(s, int(n));
#else
  return exp(x);
#endif
}

// The round trip's reprojection error (px) from x_q = `there` back towards `from`, or -1
// where it fails: the nearest pixel is unmasked, has no hypothesis, or does not project.
real roundTripError(Cam cam, vec2r from, vec2r there) {
  const int nx = lroundr(there.x), ny = lroundr(there.y);
  if (!masked(pc.mask, pc.width, pc.height, nx, ny)) return R(-1.0);
  const float qOther = pc.other.v[idx(pc.width, 2, nx, ny, 0)];
  vec3r rayOther;
  vec2r returned;
  if (qOther < 0.0 || !camUnproject(cam, there, rayOther) ||
      !projectHypothesis(cam, rayOther, -sweepTranslation(pc.prm), real(qOther), returned))
    return R(-1.0);
  precise vec2r d = returned - from;
  precise real e = sqrt(d.x * d.x + d.y * d.y);
  return e;
}

// The oracle's roundTrip at (x, y): false where it is not evaluated (no hypothesis, the
// pixel unmasked, or the match leaving the other view's valid pixels); else the pixel's
// ray, x_q = `there` and the consistency exp(-(e / tol)^2).
bool roundTripAt(Cam cam, int x, int y, out vec3r ray, out vec2r there, out float consistency) {
  consistency = 0.0;
  there = vec2r(0);
  ray = vec3r(0);
  const vec2r px = vec2r(real(x), real(y));
  const float q = pc.best.v[idx(pc.width, 2, x, y, 0)];
  if (!masked(pc.mask, pc.width, pc.height, x, y) || q < 0.0 || !camUnproject(cam, px, ray) ||
      !projectHypothesis(cam, ray, sweepTranslation(pc.prm), real(q), there))
    return false;
  const real e = roundTripError(cam, px, there);
  if (e < R(0.0)) return false;
  precise real scaled = e / real(pc.tolerancePx);
  consistency = pc.best.v[idx(pc.width, 2, x, y, 1)] > pc.maxCost ? 0.0 : float(expNonPositive(-scaled * scaled));
  return true;
}

// The oracle's setWarp: the hypothesis q at the ray as the warp (u, w), where it lands.
void setWarp(Cam cam, int x, int y, vec3r ray, real q) {
  vec2r there;
  if (!projectHypothesis(cam, ray, sweepTranslation(pc.prm), q, there)) return;
  const int i = y * pc.width + x;
  precise vec2r wq = there - vec2r(real(x), real(y));
  precise real u = sqrt(wq.x * wq.x + wq.y * wq.y);
  pc.w.v[2 * i] = float(wq.x);
  pc.w.v[2 * i + 1] = float(wq.y);
  pc.u.v[i] = float(u);
}

// The oracle's occludedSurface: one-pixel steps along d = J t / |J t| (J at the pixel's
// ray), rounded to the nearest pixel, up to pc.planes each way and stopping at the mask,
// find the first consistent pixel behind (-d) and ahead (+d). When the one behind is
// nearer (larger q), the one ahead's q; -1 otherwise.
real occludedSurface(Cam cam, vec3r ray, int x, int y) {
  vec2r at;
  vec3r J0, J1;
  if (!camProject(cam, ray, at, J0, J1)) return R(-1.0);
  const vec3r t = sweepTranslation(pc.prm);
  // Eigen's J * t: left to right, no fused multiply-adds.
  precise vec2r d = vec2r((J0.x * t.x + J0.y * t.y) + J0.z * t.z, (J1.x * t.x + J1.y * t.y) + J1.z * t.z);
  precise real norm = sqrt(d.x * d.x + d.y * d.y);
  if (!(norm > R(0.0))) return R(-1.0);
  precise vec2r dir = d / norm;
  real nearest[2] = real[2](R(-1.0), R(-1.0));  // behind, ahead
  for (int side = 0; side < 2; ++side) {
    const real sgn = side == 0 ? R(-1.0) : R(1.0);
    for (int s = 1; s <= pc.planes; ++s) {
      precise real step = sgn * real(s);
      precise real sx = real(x) + step * dir.x;
      precise real sy = real(y) + step * dir.y;
      const int nx = lroundr(sx), ny = lroundr(sy);
      if (!masked(pc.mask, pc.width, pc.height, nx, ny)) break;
      if (pc.confidence.v[ny * pc.width + nx] < pc.acceptConfidence) continue;
      nearest[side] = real(pc.best.v[idx(pc.width, 2, nx, ny, 0)]);
      break;
    }
  }
  return nearest[1] >= R(0.0) && nearest[0] > nearest[1] ? nearest[1] : R(-1.0);
}

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= pc.width || y >= pc.height) return;
  const int i = y * pc.width + x;
  const Cam cam = pc.prm.cam;
  vec3r ray;
  vec2r there;
  float consistency;

  if (pc.pass == 1) {
    // Occlusions: pass 0's inconsistent pixels whose round trip was evaluated.
    if (pc.confidence.v[i] >= pc.acceptConfidence) return;
    if (!roundTripAt(cam, x, y, ray, there, consistency)) return;
    const real q = occludedSurface(cam, ray, x, y);
    if (q >= R(0.0)) setWarp(cam, x, y, ray, q);
    return;
  }

  const bool evaluated = roundTripAt(cam, x, y, ray, there, consistency);
  pc.confidence.v[i] = consistency;
  if (!evaluated || consistency < pc.acceptConfidence) return;  // keep the coarse-to-fine estimate
  precise vec2r wq = there - vec2r(real(x), real(y));
  precise real u = sqrt(wq.x * wq.x + wq.y * wq.y);
  pc.w.v[2 * i] = float(wq.x);
  pc.w.v[2 * i + 1] = float(wq.y);
  pc.u.v[i] = float(u);
}

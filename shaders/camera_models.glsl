// The camera models of core/include/curvestereo/camera_models.hpp, operation by operation:
// project (with the 2x3 Jacobian as two rows) and unproject for Kannala-Brandt 4, Unified,
// Extended Unified, Double Sphere, pinhole + radtan and MEI (unified + radtan). Per-lens
// constants the C++ constructors derive (KB turning angle and radius, the unified-family w,
// MEI's undistorted radius bound) come from the host.
#ifndef CS_CAMERA_MODELS_GLSL
#define CS_CAMERA_MODELS_GLSL
#include "real.glsl"

// Mirrors VkCam<S> in backend_vulkan/vulkan_backend.cpp (std430).
struct Cam {
  int model, width, height, pad;
  real p[12];  // fx fy cx cy extra... (cs::kMaxCameraParams)
  real d[4];   // KB: thetaMax, radiusMax; unified family: w; radtan: unused; MEI: w, rMax
};

const int kKannalaBrandt4 = 0, kUnified = 1, kExtendedUnified = 2, kDoubleSphere = 3, kPinholeRadtan = 4, kMei = 5;

vec2r toNormalized(Cam c, vec2r px) { return vec2r((px.x - c.p[2]) / c.p[0], (px.y - c.p[3]) / c.p[1]); }
real norm3(vec3r v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }
vec3r normalized3(vec3r v) {
  real n2 = v.x * v.x + v.y * v.y + v.z * v.z;
  return n2 > R(0.0) ? v / sqrt(n2) : v;
}

// ---- Kannala-Brandt 4 ----
real kbDistort(Cam c, real th) {
  real t2 = th * th;
  return th * (R(1.0) + t2 * (c.p[4] + t2 * (c.p[5] + t2 * (c.p[6] + t2 * c.p[7]))));
}
real kbDistortDerivative(Cam c, real th) {
  real t2 = th * th;
  return R(1.0) + t2 * (R(3.0) * c.p[4] + t2 * (R(5.0) * c.p[5] + t2 * (R(7.0) * c.p[6] + t2 * R(9.0) * c.p[7])));
}
bool kbProject(Cam c, vec3r p, out vec2r px, out vec3r J0, out vec3r J1) {
  px = vec2r(0); J0 = vec3r(0); J1 = vec3r(0);
  real x = p.x, y = p.y, z = p.z;
  real r2 = x * x + y * y;
  real rho2 = r2 + z * z;
  if (!(rho2 > R(0.0))) return false;
  real r = sqrt(r2);
  real th = atan2r(r, z);
  if (!(th < c.d[0])) return false;
  real s = r > R(0.0) ? kbDistort(c, th) / r : R(1.0) / z;
  px = vec2r(c.p[0] * (s * x) + c.p[2], c.p[1] * (s * y) + c.p[3]);
  real dd = kbDistortDerivative(c, th);
  bool nearAxis = z > R(0.0) && r2 < EPS * rho2;
  real A = nearAxis ? R(2.0) * (c.p[4] - R(1.0) / R(3.0)) / (z * z * z) : (dd * z / rho2 - s) / r2;
  real B = -dd / rho2;
  J0 = vec3r(c.p[0] * (s + x * x * A), c.p[0] * x * y * A, c.p[0] * x * B);
  J1 = vec3r(c.p[1] * x * y * A, c.p[1] * (s + y * y * A), c.p[1] * y * B);
  return true;
}
real kbSolveTheta(Cam c, real rd) {
  real lo = R(0.0), hi = c.d[0];
  real th = rd < hi ? rd : R(0.5) * hi;
  for (int it = 0; it < 60; ++it) {
    real f = kbDistort(c, th) - rd;
    if (f == R(0.0)) break;
    if (f < R(0.0)) lo = th; else hi = th;
    real next = th - f / kbDistortDerivative(c, th);
    if (!(next > lo && next < hi)) next = R(0.5) * (lo + hi);
    real step = abs(next - th);
    th = next;
    if (step <= R(4.0) * EPS * th) break;
  }
  return th;
}
bool kbUnproject(Cam c, vec2r px, out vec3r ray) {
  ray = vec3r(0);
  vec2r m = toNormalized(c, px);
  real rd = sqrt(m.x * m.x + m.y * m.y);
  if (!(rd < c.d[1])) return false;
  if (rd == R(0.0)) {
    ray = vec3r(R(0.0), R(0.0), R(1.0));
    return true;
  }
  real th = kbSolveTheta(c, rd);
  real sn, cs;
  sincosr(th, sn, cs);
  real sinOverRd = sn / rd;
  ray = vec3r(m.x * sinOverRd, m.y * sinOverRd, cs);
  return true;
}

// ---- rational models: px = f (x, y) / den + c ----
void projectRational(Cam c, vec3r p, real den, vec3r gradDen, out vec2r px, out vec3r J0, out vec3r J1) {
  real inv = R(1.0) / den;
  px = vec2r(c.p[0] * (p.x * inv) + c.p[2], c.p[1] * (p.y * inv) + c.p[3]);
  real inv2 = inv * inv;
  J0 = (-c.p[0] * p.x * inv2) * gradDen;
  J1 = (-c.p[1] * p.y * inv2) * gradDen;
  J0.x += c.p[0] * inv;
  J1.y += c.p[1] * inv;
}

bool unifiedProject(Cam c, vec3r p, out vec2r px, out vec3r J0, out vec3r J1) {
  px = vec2r(0); J0 = vec3r(0); J1 = vec3r(0);
  real xi = c.p[4], w = c.d[0];
  real d = norm3(p);
  if (!(p.z > -w * d)) return false;
  real den = p.z + xi * d;
  if (!(den > R(0.0))) return false;
  vec3r gradDen = (xi / d) * p + vec3r(R(0.0), R(0.0), R(1.0));
  projectRational(c, p, den, gradDen, px, J0, J1);
  return true;
}
bool unifiedUnproject(Cam c, vec2r px, out vec3r ray) {
  ray = vec3r(0);
  real xi = c.p[4], w = c.d[0];
  vec2r m = toNormalized(c, px);
  real r2 = m.x * m.x + m.y * m.y;
  real disc = R(1.0) + (R(1.0) - xi * xi) * r2;
  if (!(disc >= R(0.0))) return false;
  real factor = (xi + sqrt(disc)) / (R(1.0) + r2);
  ray = normalized3(vec3r(factor * m.x, factor * m.y, factor - xi));
  return ray.z > -w * norm3(ray);
}

real eucmDistance(Cam c, vec3r p) { return sqrt(c.p[5] * (p.x * p.x + p.y * p.y) + p.z * p.z); }
bool eucmProject(Cam c, vec3r p, out vec2r px, out vec3r J0, out vec3r J1) {
  px = vec2r(0); J0 = vec3r(0); J1 = vec3r(0);
  real alpha = c.p[4], beta = c.p[5], w = c.d[0];
  real d = eucmDistance(c, p);
  if (!(p.z > -w * d)) return false;
  real den = alpha * d + (R(1.0) - alpha) * p.z;
  if (!(den > R(0.0))) return false;
  vec3r gradD = vec3r(beta * p.x, beta * p.y, p.z) / d;
  vec3r gradDen = alpha * gradD + vec3r(R(0.0), R(0.0), R(1.0) - alpha);
  projectRational(c, p, den, gradDen, px, J0, J1);
  return true;
}
bool eucmUnproject(Cam c, vec2r px, out vec3r ray) {
  ray = vec3r(0);
  real alpha = c.p[4], beta = c.p[5], w = c.d[0];
  vec2r m = toNormalized(c, px);
  real r2 = m.x * m.x + m.y * m.y;
  real disc = R(1.0) - (R(2.0) * alpha - R(1.0)) * beta * r2;
  if (!(disc >= R(0.0))) return false;
  real mz = (R(1.0) - beta * alpha * alpha * r2) / (alpha * sqrt(disc) + R(1.0) - alpha);
  ray = normalized3(vec3r(m.x, m.y, mz));
  return ray.z > -w * eucmDistance(c, ray);
}

bool dsProject(Cam c, vec3r p, out vec2r px, out vec3r J0, out vec3r J1) {
  px = vec2r(0); J0 = vec3r(0); J1 = vec3r(0);
  real xi = c.p[4], alpha = c.p[5], w2 = c.d[0];
  real d1 = norm3(p);
  if (!(p.z > -w2 * d1)) return false;
  real k = xi * d1 + p.z;
  real d2 = sqrt(p.x * p.x + p.y * p.y + k * k);
  real den = alpha * d2 + (R(1.0) - alpha) * k;
  if (!(den > R(0.0))) return false;
  vec3r gradK = (xi / d1) * p + vec3r(R(0.0), R(0.0), R(1.0));
  vec3r gradD2 = (vec3r(p.x, p.y, R(0.0)) + k * gradK) / d2;
  vec3r gradDen = alpha * gradD2 + (R(1.0) - alpha) * gradK;
  projectRational(c, p, den, gradDen, px, J0, J1);
  return true;
}
bool dsUnproject(Cam c, vec2r px, out vec3r ray) {
  ray = vec3r(0);
  real xi = c.p[4], alpha = c.p[5], w2 = c.d[0];
  vec2r m = toNormalized(c, px);
  real r2 = m.x * m.x + m.y * m.y;
  real disc1 = R(1.0) - (R(2.0) * alpha - R(1.0)) * r2;
  if (!(disc1 >= R(0.0))) return false;
  real mz = (R(1.0) - alpha * alpha * r2) / (alpha * sqrt(disc1) + R(1.0) - alpha);
  real disc2 = mz * mz + (R(1.0) - xi * xi) * r2;
  if (!(disc2 >= R(0.0))) return false;
  real factor = (mz * xi + sqrt(disc2)) / (mz * mz + r2);
  ray = normalized3(vec3r(factor * m.x, factor * m.y, factor * mz - xi));
  return ray.z > -w2 * norm3(ray);
}

// ---- radial-tangential distortion: coefficients at p[o..o+3] (pinhole o = 4, MEI o = 5) ----
// Distorted normalised point; Jd rows (d00 d01) (d10 d11).
vec2r radtanDistort(Cam c, int o, vec2r n, out vec2r Jd0, out vec2r Jd1) {
  real k1 = c.p[o], k2 = c.p[o + 1], p1 = c.p[o + 2], p2 = c.p[o + 3];
  real x = n.x, y = n.y;
  real r2 = x * x + y * y;
  real radial = R(1.0) + r2 * (k1 + r2 * k2);
  vec2r v = vec2r(x * radial + R(2.0) * p1 * x * y + p2 * (r2 + R(2.0) * x * x),
                  y * radial + p1 * (r2 + R(2.0) * y * y) + R(2.0) * p2 * x * y);
  real dRadial = R(2.0) * (k1 + R(2.0) * k2 * r2);
  real off = x * y * dRadial + R(2.0) * p1 * x + R(2.0) * p2 * y;
  Jd0 = vec2r(radial + x * x * dRadial + R(2.0) * p1 * y + R(6.0) * p2 * x, off);
  Jd1 = vec2r(off, radial + y * y * dRadial + R(6.0) * p1 * y + R(2.0) * p2 * x);
  return v;
}
bool finite2(vec2r v) { return !(isnan(v.x) || isnan(v.y) || isinf(v.x) || isinf(v.y)); }
// Newton from n = start; false when it does not reach m (Radtan::undistort).
bool radtanUndistort(Cam c, int o, vec2r m, vec2r start, out vec2r n) {
  n = start;
  if (!finite2(m) || !finite2(start)) return false;
  vec2r Jd0, Jd1;
  for (int it = 0; it < 20; ++it) {
    vec2r res = radtanDistort(c, o, n, Jd0, Jd1) - m;
    real det = Jd0.x * Jd1.y - Jd0.y * Jd1.x;
    if (!(abs(det) > EPS)) return false;
    vec2r step = vec2r((Jd1.y * res.x - Jd0.y * res.y) / det, (Jd0.x * res.y - Jd1.x * res.x) / det);
    n -= step;
    if (sqrt(step.x * step.x + step.y * step.y) <= R(16.0) * EPS * (R(1.0) + sqrt(n.x * n.x + n.y * n.y))) break;
  }
  real accepted = sqrt(EPS) * (R(1.0) + sqrt(m.x * m.x + m.y * m.y));
  vec2r e = radtanDistort(c, o, n, Jd0, Jd1) - m;
  return sqrt(e.x * e.x + e.y * e.y) <= accepted;
}

// r in [0, rMax] with r (1 + k1 r^2 + k2 r^4) = rd (Radtan::solveRadius).
real radtanSolveRadius(Cam c, int o, real rd, real rMax) {
  real k1 = c.p[o], k2 = c.p[o + 1];
  real lo = R(0.0), hi = rMax;
  real r = rd < hi ? rd : R(0.5) * hi;
  for (int it = 0; it < 60; ++it) {
    real r2 = r * r;
    real f = r * (R(1.0) + r2 * (k1 + r2 * k2)) - rd;
    if (f == R(0.0)) break;
    if (f < R(0.0)) lo = r; else hi = r;
    real next = r - f / (R(1.0) + r2 * (R(3.0) * k1 + R(5.0) * k2 * r2));
    if (!(next > lo && next < hi)) next = R(0.5) * (lo + hi);
    real step = abs(next - r);
    r = next;
    if (step <= R(4.0) * EPS * r) break;
  }
  return r;
}

// ---- pinhole + radial-tangential ----
bool radtanProject(Cam c, vec3r p, out vec2r px, out vec3r J0, out vec3r J1) {
  px = vec2r(0); J0 = vec3r(0); J1 = vec3r(0);
  if (!(p.z > D(1e-6LF, 1e-6) * norm3(p))) return false;
  real iz = R(1.0) / p.z;
  vec2r n = vec2r(p.x * iz, p.y * iz);
  vec2r Jd0, Jd1;
  vec2r md = radtanDistort(c, 4, n, Jd0, Jd1);
  px = vec2r(c.p[0] * md.x + c.p[2], c.p[1] * md.y + c.p[3]);
  // J = diag(fx, fy) Jd Jn with Jn = (iz 0 -nx iz; 0 iz -ny iz).
  vec2r a0 = c.p[0] * Jd0, a1 = c.p[1] * Jd1;
  J0 = vec3r(a0.x * iz, a0.y * iz, a0.x * (-n.x * iz) + a0.y * (-n.y * iz));
  J1 = vec3r(a1.x * iz, a1.y * iz, a1.x * (-n.x * iz) + a1.y * (-n.y * iz));
  return true;
}
bool radtanUnproject(Cam c, vec2r px, out vec3r ray) {
  ray = vec3r(0);
  vec2r m = toNormalized(c, px);
  vec2r n;
  if (!radtanUndistort(c, 4, m, m, n)) return false;
  ray = normalized3(vec3r(n.x, n.y, R(1.0)));
  return true;
}

// ---- MEI: unified projection m = (x, y) / (z + xi |p|), then radtan of m ----
bool meiProject(Cam c, vec3r p, out vec2r px, out vec3r J0, out vec3r J1) {
  px = vec2r(0); J0 = vec3r(0); J1 = vec3r(0);
  real xi = c.p[4], w = c.d[0], rMax = c.d[1];
  real d = norm3(p);
  if (!(p.z > -w * d)) return false;
  real den = p.z + xi * d;
  if (!(den > R(0.0))) return false;
  real inv = R(1.0) / den;
  vec2r m = vec2r(p.x * inv, p.y * inv);
  if (!(sqrt(m.x * m.x + m.y * m.y) < rMax)) return false;
  vec2r Jd0, Jd1;
  vec2r md = radtanDistort(c, 5, m, Jd0, Jd1);
  px = vec2r(c.p[0] * md.x + c.p[2], c.p[1] * md.y + c.p[3]);
  // J = diag(fx, fy) Jd Jm, Jm rows (e_x - m.x g) / den, (e_y - m.y g) / den, g = grad(den).
  vec3r g = (xi / d) * p + vec3r(R(0.0), R(0.0), R(1.0));
  vec3r m0 = (-m.x * inv) * g, m1 = (-m.y * inv) * g;
  m0.x += inv;
  m1.y += inv;
  vec2r a0 = c.p[0] * Jd0, a1 = c.p[1] * Jd1;
  J0 = a0.x * m0 + a0.y * m1;
  J1 = a1.x * m0 + a1.y * m1;
  return true;
}
bool meiUnproject(Cam c, vec2r px, out vec3r ray) {
  ray = vec3r(0);
  real xi = c.p[4], w = c.d[0], rMax = c.d[1];
  vec2r md = toNormalized(c, px);
  if (!finite2(md)) return false;
  real rd = sqrt(md.x * md.x + md.y * md.y);
  vec2r start = rd > R(0.0) ? md * (radtanSolveRadius(c, 5, rd, rMax) / rd) : md;
  vec2r m;
  if (!radtanUndistort(c, 5, md, start, m)) return false;
  real r2 = m.x * m.x + m.y * m.y;
  if (!(sqrt(r2) < rMax)) return false;
  real disc = R(1.0) + (R(1.0) - xi * xi) * r2;
  if (!(disc >= R(0.0))) return false;
  real factor = (xi + sqrt(disc)) / (R(1.0) + r2);
  ray = normalized3(vec3r(factor * m.x, factor * m.y, factor - xi));
  return ray.z > -w * norm3(ray);
}

// ---- dispatch on the model ----
bool camProject(Cam c, vec3r p, out vec2r px, out vec3r J0, out vec3r J1) {
  if (c.model == kUnified) return unifiedProject(c, p, px, J0, J1);
  if (c.model == kExtendedUnified) return eucmProject(c, p, px, J0, J1);
  if (c.model == kDoubleSphere) return dsProject(c, p, px, J0, J1);
  if (c.model == kPinholeRadtan) return radtanProject(c, p, px, J0, J1);
  if (c.model == kMei) return meiProject(c, p, px, J0, J1);
  return kbProject(c, p, px, J0, J1);
}
bool camUnproject(Cam c, vec2r px, out vec3r ray) {
  if (c.model == kUnified) return unifiedUnproject(c, px, ray);
  if (c.model == kExtendedUnified) return eucmUnproject(c, px, ray);
  if (c.model == kDoubleSphere) return dsUnproject(c, px, ray);
  if (c.model == kPinholeRadtan) return radtanUnproject(c, px, ray);
  if (c.model == kMei) return meiUnproject(c, px, ray);
  return kbUnproject(c, px, ray);
}
bool camInImage(Cam c, vec2r px) {
  return px.x >= R(-0.5) && px.y >= R(-0.5) && px.x <= real(c.width) - R(0.5) && px.y <= real(c.height) - R(0.5);
}

#endif

// The camera models of core/include/curvestereo/camera_models.hpp on the device, in
// double precision like the oracle: the same equations, branches and iteration limits.
// What the host constructors precompute (Kannala-Brandt turning angle, valid-region
// bounds) arrives in CameraParams::constants (toCameraParams).
#pragma once
#include "common.cuh"

namespace cs::cudak {

struct V2 {
  double x, y;
};
struct V3 {
  double x, y, z;
};

// The estimate (u, w) of pixel (x, y) whose match lands at `there`: w in float, u = |w| (the
// oracle's storeWarp).
__device__ inline void storeWarp(const Img& u, const Img& w, const V2& there, int x, int y) {
  const double wx = there.x - x, wy = there.y - y;
  at(w, x, y, 0) = float(wx);
  at(w, x, y, 1) = float(wy);
  at(u, x, y) = float(sqrt(wx * wx + wy * wy));
}

// CameraModel's order.
enum : int { kKannalaBrandt4 = 0, kUnified = 1, kExtendedUnified = 2, kDoubleSphere = 3, kPinholeRadtan = 4, kMei = 5 };
constexpr double kEpsD = 2.220446049250313080847e-16;

__device__ __forceinline__ double norm3(const V3& p) { return sqrt(p.x * p.x + p.y * p.y + p.z * p.z); }
// Eigen's normalized(): unchanged when the norm is zero.
__device__ __forceinline__ V3 normalized(const V3& p) {
  const double n2 = p.x * p.x + p.y * p.y + p.z * p.z;
  if (!(n2 > 0)) return p;
  const double n = sqrt(n2);
  return {p.x / n, p.y / n, p.z / n};
}

struct J23 {
  double m[2][3];
};

__device__ __forceinline__ V2 toNormalized(const CameraParams& c, double px, double py) {
  return {(px - c.params[2]) / c.params[0], (py - c.params[3]) / c.params[1]};
}
__device__ __forceinline__ V2 toPixel(const CameraParams& c, double mx, double my) {
  return {c.params[0] * mx + c.params[2], c.params[1] * my + c.params[3]};
}

__device__ __forceinline__ void projectRational(const CameraParams& c, const V3& p, double den, const V3& gradDen,
                                                V2& px, J23* J) {
  const double inv = 1.0 / den;
  px = toPixel(c, p.x * inv, p.y * inv);
  if (!J) return;
  const double inv2 = inv * inv;
  const double r0 = -c.params[0] * p.x * inv2, r1 = -c.params[1] * p.y * inv2;
  J->m[0][0] = r0 * gradDen.x, J->m[0][1] = r0 * gradDen.y, J->m[0][2] = r0 * gradDen.z;
  J->m[1][0] = r1 * gradDen.x, J->m[1][1] = r1 * gradDen.y, J->m[1][2] = r1 * gradDen.z;
  J->m[0][0] += c.params[0] * inv;
  J->m[1][1] += c.params[1] * inv;
}

// --- Kannala-Brandt 4 ---
__device__ __forceinline__ double kbDistort(const CameraParams& c, double th) {
  const double t2 = th * th;
  return th * (1.0 + t2 * (c.params[4] + t2 * (c.params[5] + t2 * (c.params[6] + t2 * c.params[7]))));
}
__device__ __forceinline__ double kbDistortDerivative(const CameraParams& c, double th) {
  const double t2 = th * th;
  return 1.0 + t2 * (3.0 * c.params[4] + t2 * (5.0 * c.params[5] + t2 * (7.0 * c.params[6] + t2 * 9.0 * c.params[7])));
}
__device__ inline bool kbProject(const CameraParams& c, const V3& p, V2& px, J23* J) {
  const double x = p.x, y = p.y, z = p.z;
  const double r2 = x * x + y * y;
  const double rho2 = r2 + z * z;
  if (!(rho2 > 0)) return false;
  const double r = sqrt(r2);
  const double th = atan2(r, z);
  if (!(th < c.constants.a)) return false;
  const double s = r > 0 ? kbDistort(c, th) / r : 1.0 / z;
  px = toPixel(c, s * x, s * y);
  if (!J) return true;
  const double dd = kbDistortDerivative(c, th);
  const bool nearAxis = z > 0 && r2 < kEpsD * rho2;
  const double A = nearAxis ? 2.0 * (c.params[4] - 1.0 / 3.0) / (z * z * z) : (dd * z / rho2 - s) / r2;
  const double B = -dd / rho2;
  const double fx = c.params[0], fy = c.params[1];
  J->m[0][0] = fx * (s + x * x * A), J->m[0][1] = fx * x * y * A, J->m[0][2] = fx * x * B;
  J->m[1][0] = fy * x * y * A, J->m[1][1] = fy * (s + y * y * A), J->m[1][2] = fy * y * B;
  return true;
}
__device__ inline double kbSolveTheta(const CameraParams& c, double rd) {
  double lo = 0, hi = c.constants.a;
  double th = rd < hi ? rd : 0.5 * hi;
  for (int it = 0; it < 60; ++it) {
    const double f = kbDistort(c, th) - rd;
    if (f == 0) break;
    (f < 0 ? lo : hi) = th;
    double next = th - f / kbDistortDerivative(c, th);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double stp = fabs(next - th);
    th = next;
    if (stp <= 4.0 * kEpsD * th) break;
  }
  return th;
}
__device__ inline bool kbUnproject(const CameraParams& c, double px, double py, V3& ray) {
  const V2 m = toNormalized(c, px, py);
  const double rd = sqrt(m.x * m.x + m.y * m.y);
  if (!(rd < c.constants.b)) return false;
  if (rd == 0) {
    ray = {0, 0, 1};
    return true;
  }
  const double th = kbSolveTheta(c, rd);
  const double sinOverRd = sin(th) / rd;
  ray = {m.x * sinOverRd, m.y * sinOverRd, cos(th)};
  return true;
}

// --- Unified ---
__device__ inline bool ucmProject(const CameraParams& c, const V3& p, V2& px, J23* J) {
  const double xi = c.params[4], w = c.constants.a;
  const double d = norm3(p);
  if (!(p.z > -w * d)) return false;
  const double den = p.z + xi * d;
  if (!(den > 0)) return false;
  const double k = xi / d;
  projectRational(c, p, den, V3{k * p.x, k * p.y, k * p.z + 1.0}, px, J);
  return true;
}
__device__ inline bool ucmUnproject(const CameraParams& c, double px, double py, V3& ray) {
  const double xi = c.params[4], w = c.constants.a;
  const V2 m = toNormalized(c, px, py);
  const double r2 = m.x * m.x + m.y * m.y;
  const double disc = 1.0 + (1.0 - xi * xi) * r2;
  if (!(disc >= 0)) return false;
  const double factor = (xi + sqrt(disc)) / (1.0 + r2);
  ray = normalized(V3{factor * m.x, factor * m.y, factor - xi});
  return ray.z > -w * norm3(ray);
}

// --- Extended unified ---
__device__ __forceinline__ double eucmDistance(double beta, const V3& p) {
  return sqrt(beta * (p.x * p.x + p.y * p.y) + p.z * p.z);
}
__device__ inline bool eucmProject(const CameraParams& c, const V3& p, V2& px, J23* J) {
  const double alpha = c.params[4], beta = c.params[5], w = c.constants.a;
  const double d = eucmDistance(beta, p);
  if (!(p.z > -w * d)) return false;
  const double den = alpha * d + (1.0 - alpha) * p.z;
  if (!(den > 0)) return false;
  const V3 gradD{beta * p.x / d, beta * p.y / d, p.z / d};
  projectRational(c, p, den, V3{alpha * gradD.x, alpha * gradD.y, alpha * gradD.z + (1.0 - alpha)}, px, J);
  return true;
}
__device__ inline bool eucmUnproject(const CameraParams& c, double px, double py, V3& ray) {
  const double alpha = c.params[4], beta = c.params[5], w = c.constants.a;
  const V2 m = toNormalized(c, px, py);
  const double r2 = m.x * m.x + m.y * m.y;
  const double disc = 1.0 - (2.0 * alpha - 1.0) * beta * r2;
  if (!(disc >= 0)) return false;
  const double mz = (1.0 - beta * alpha * alpha * r2) / (alpha * sqrt(disc) + 1.0 - alpha);
  ray = normalized(V3{m.x, m.y, mz});
  return ray.z > -w * eucmDistance(beta, ray);
}

// --- Double sphere ---
__device__ inline bool dsProject(const CameraParams& c, const V3& p, V2& px, J23* J) {
  const double xi = c.params[4], alpha = c.params[5], w2 = c.constants.a;
  const double d1 = norm3(p);
  if (!(p.z > -w2 * d1)) return false;
  const double k = xi * d1 + p.z;
  const double d2 = sqrt(p.x * p.x + p.y * p.y + k * k);
  const double den = alpha * d2 + (1.0 - alpha) * k;
  if (!(den > 0)) return false;
  const double kk = xi / d1;
  const V3 gradK{kk * p.x, kk * p.y, kk * p.z + 1.0};
  const V3 gradD2{(p.x + k * gradK.x) / d2, (p.y + k * gradK.y) / d2, (0.0 + k * gradK.z) / d2};
  const V3 gradDen{alpha * gradD2.x + (1.0 - alpha) * gradK.x, alpha * gradD2.y + (1.0 - alpha) * gradK.y,
                   alpha * gradD2.z + (1.0 - alpha) * gradK.z};
  projectRational(c, p, den, gradDen, px, J);
  return true;
}
__device__ inline bool dsUnproject(const CameraParams& c, double px, double py, V3& ray) {
  const double xi = c.params[4], alpha = c.params[5], w2 = c.constants.a;
  const V2 m = toNormalized(c, px, py);
  const double r2 = m.x * m.x + m.y * m.y;
  const double disc1 = 1.0 - (2.0 * alpha - 1.0) * r2;
  if (!(disc1 >= 0)) return false;
  const double mz = (1.0 - alpha * alpha * r2) / (alpha * sqrt(disc1) + 1.0 - alpha);
  const double disc2 = mz * mz + (1.0 - xi * xi) * r2;
  if (!(disc2 >= 0)) return false;
  const double factor = (mz * xi + sqrt(disc2)) / (mz * mz + r2);
  ray = normalized(V3{factor * m.x, factor * m.y, factor * mz - xi});
  return ray.z > -w2 * norm3(ray);
}

// --- Radial-tangential distortion (pinhole: coefficients at p[4], MEI: at p[5]) ---
__device__ __forceinline__ V2 rtDistort(const double* k, double x, double y, double Jd[2][2]) {
  const double k1 = k[0], k2 = k[1], p1 = k[2], p2 = k[3];
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * k2);
  const V2 out{x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
               y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y};
  if (Jd) {
    const double dRadial = 2.0 * (k1 + 2.0 * k2 * r2);
    Jd[0][0] = radial + x * x * dRadial + 2.0 * p1 * y + 6.0 * p2 * x;
    Jd[0][1] = x * y * dRadial + 2.0 * p1 * x + 2.0 * p2 * y;
    Jd[1][0] = x * y * dRadial + 2.0 * p1 * x + 2.0 * p2 * y;
    Jd[1][1] = radial + y * y * dRadial + 6.0 * p1 * y + 2.0 * p2 * x;
  }
  return out;
}
// Radtan::undistort: Newton from n = start, accepted when it reaches m.
__device__ inline bool rtUndistort(const double* k, const V2& m, const V2& start, V2& n) {
  if (!isfinite(m.x) || !isfinite(m.y) || !isfinite(start.x) || !isfinite(start.y)) return false;
  double nx = start.x, ny = start.y;
  double Jd[2][2];
  for (int it = 0; it < 20; ++it) {
    const V2 d = rtDistort(k, nx, ny, Jd);
    const double rx = d.x - m.x, ry = d.y - m.y;
    const double det = Jd[0][0] * Jd[1][1] - Jd[0][1] * Jd[1][0];
    if (!(fabs(det) > kEpsD)) return false;
    const double sx = (Jd[1][1] * rx - Jd[0][1] * ry) / det, sy = (Jd[0][0] * ry - Jd[1][0] * rx) / det;
    nx -= sx;
    ny -= sy;
    if (sqrt(sx * sx + sy * sy) <= 16.0 * kEpsD * (1.0 + sqrt(nx * nx + ny * ny))) break;
  }
  const double accepted = sqrt(kEpsD) * (1.0 + sqrt(m.x * m.x + m.y * m.y));
  const V2 d = rtDistort(k, nx, ny, nullptr);
  const double ex = d.x - m.x, ey = d.y - m.y;
  n = {nx, ny};
  return sqrt(ex * ex + ey * ey) <= accepted;
}
// Radtan::solveRadius: r in [0, rMax] with r (1 + k1 r^2 + k2 r^4) = rd.
__device__ inline double rtSolveRadius(const double* k, double rd, double rMax) {
  const double k1 = k[0], k2 = k[1];
  double lo = 0, hi = rMax;
  double r = rd < hi ? rd : 0.5 * hi;
  for (int it = 0; it < 60; ++it) {
    const double r2 = r * r;
    const double f = r * (1.0 + r2 * (k1 + r2 * k2)) - rd;
    if (f == 0) break;
    (f < 0 ? lo : hi) = r;
    double next = r - f / (1.0 + r2 * (3.0 * k1 + 5.0 * k2 * r2));
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double stp = fabs(next - r);
    r = next;
    if (stp <= 4.0 * kEpsD * r) break;
  }
  return r;
}
// d(px)/d(p) = diag(f) Jd Jn for the 2x3 Jacobian Jn of the undistorted point.
__device__ __forceinline__ void rtChain(const CameraParams& c, const double Jd[2][2], const double Jn[2][3], J23* J) {
  const double f[2] = {c.params[0], c.params[1]};
  for (int r = 0; r < 2; ++r)
    for (int col = 0; col < 3; ++col) J->m[r][col] = f[r] * (Jd[r][0] * Jn[0][col] + Jd[r][1] * Jn[1][col]);
}

// --- Pinhole + radial-tangential ---
__device__ inline bool rtProject(const CameraParams& c, const V3& p, V2& px, J23* J) {
  if (!(p.z > 1e-6 * norm3(p))) return false;
  const double iz = 1.0 / p.z;
  const double nx = p.x * iz, ny = p.y * iz;
  double Jd[2][2];
  const V2 md = rtDistort(c.params + 4, nx, ny, J ? Jd : nullptr);
  px = toPixel(c, md.x, md.y);
  if (!J) return true;
  const double Jn[2][3] = {{iz, 0, -nx * iz}, {0, iz, -ny * iz}};
  rtChain(c, Jd, Jn, J);
  return true;
}
__device__ inline bool rtUnproject(const CameraParams& c, double px, double py, V3& ray) {
  const V2 m = toNormalized(c, px, py);
  V2 n;
  if (!rtUndistort(c.params + 4, m, m, n)) return false;
  ray = normalized(V3{n.x, n.y, 1.0});
  return true;
}

// --- MEI: unified projection, then radial-tangential distortion ---
__device__ inline bool meiProject(const CameraParams& c, const V3& p, V2& px, J23* J) {
  const double xi = c.params[4], w = c.constants.a, rMax = c.constants.b;
  const double d = norm3(p);
  if (!(p.z > -w * d)) return false;
  const double den = p.z + xi * d;
  if (!(den > 0)) return false;
  const double inv = 1.0 / den;
  const double mx = p.x * inv, my = p.y * inv;
  if (!(sqrt(mx * mx + my * my) < rMax)) return false;
  double Jd[2][2];
  const V2 md = rtDistort(c.params + 5, mx, my, J ? Jd : nullptr);
  px = toPixel(c, md.x, md.y);
  if (!J) return true;
  const double k = xi / d;
  const double g[3] = {k * p.x, k * p.y, k * p.z + 1.0};
  const double a0 = -mx * inv, a1 = -my * inv;
  const double Jm[2][3] = {{a0 * g[0] + inv, a0 * g[1], a0 * g[2]}, {a1 * g[0], a1 * g[1] + inv, a1 * g[2]}};
  rtChain(c, Jd, Jm, J);
  return true;
}
__device__ inline bool meiUnproject(const CameraParams& c, double px, double py, V3& ray) {
  const double xi = c.params[4], w = c.constants.a, rMax = c.constants.b;
  const V2 md = toNormalized(c, px, py);
  if (!isfinite(md.x) || !isfinite(md.y)) return false;
  const double rd = sqrt(md.x * md.x + md.y * md.y);
  V2 start = md;
  if (rd > 0) {
    const double s = rtSolveRadius(c.params + 5, rd, rMax) / rd;
    start = {md.x * s, md.y * s};
  }
  V2 m;
  if (!rtUndistort(c.params + 5, md, start, m)) return false;
  const double r2 = m.x * m.x + m.y * m.y;
  if (!(sqrt(r2) < rMax)) return false;
  const double disc = 1.0 + (1.0 - xi * xi) * r2;
  if (!(disc >= 0)) return false;
  const double factor = (xi + sqrt(disc)) / (1.0 + r2);
  ray = normalized(V3{factor * m.x, factor * m.y, factor - xi});
  return ray.z > -w * norm3(ray);
}

__device__ inline bool cameraProject(const CameraParams& c, const V3& p, V2& px, J23* J = nullptr) {
  switch (c.model) {
    case kUnified:
      return ucmProject(c, p, px, J);
    case kExtendedUnified:
      return eucmProject(c, p, px, J);
    case kDoubleSphere:
      return dsProject(c, p, px, J);
    case kPinholeRadtan:
      return rtProject(c, p, px, J);
    case kMei:
      return meiProject(c, p, px, J);
    default:
      return kbProject(c, p, px, J);
  }
}
__device__ inline bool cameraUnproject(const CameraParams& c, double px, double py, V3& ray) {
  switch (c.model) {
    case kUnified:
      return ucmUnproject(c, px, py, ray);
    case kExtendedUnified:
      return eucmUnproject(c, px, py, ray);
    case kDoubleSphere:
      return dsUnproject(c, px, py, ray);
    case kPinholeRadtan:
      return rtUnproject(c, px, py, ray);
    case kMei:
      return meiUnproject(c, px, py, ray);
    default:
      return kbUnproject(c, px, py, ray);
  }
}

}  // namespace cs::cudak

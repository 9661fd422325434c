// The camera models as small value types: one struct per model, templated on the scalar,
// and AnyModel<S>, the run-time choice among them (a std::variant in CameraModel's order).
//
// Each model is built from the Camera parameter layout [fx fy cx cy extra...] and has
//   bool project(p, px, J*)   p in the camera frame -> pixel, optional 2x3 d(px)/d(p)
//   bool unproject(px, ray)   pixel -> unit ray
//   bool validPoint(p)        p inside the region the model projects one-to-one
//   double maxAngle()         largest angle to the optical axis of that region
//   precomputed()             what the constructor derived that the GPU kernels' copies of
//                             the model read instead of deriving it per pixel (2 values)
// and states its facts once, as static members, for code that holds only a CameraModel
// (visitModelType below is the one place that maps one to its model):
//   kModel, kName             its CameraModel and its name in messages
//   kNumParams, kParamNames   the length of Camera::params and each entry's name
//   kDistortionParams         the trailing entries that are a distortion (Kalibr's
//                             distortion_coeffs), the rest being the projection's
//   kKalibrModel, kKalibrDistortion   Kalibr's camera_model and distortion_model
//   checkParams(p, fail)      calls fail(index, problem) for the first entry outside the
//                             model's domain ("is negative"), beyond Camera::validate's checks
// The constructors precompute what every call needs (e.g. the Kannala-Brandt turning
// angle, a scan of the distortion polynomial), so build a model once per camera, not per
// pixel: cs::BuiltCamera (camera.hpp) holds one built from a Camera.
//
// Written from the published model equations: Kannala & Brandt (2006), Geyer &
// Daniilidis / Mei & Rives (unified), Khomenko et al. (2016, extended unified),
// Usenko, Demmel & Cremers (2018, double sphere, incl. the valid regions used here), Mei &
// Rives (2007, unified projection followed by radial-tangential distortion).
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>
#include <variant>

namespace cs {

template <class S>
using Vec2 = Eigen::Matrix<S, 2, 1>;
template <class S>
using Vec3 = Eigen::Matrix<S, 3, 1>;
template <class S>
using Mat23 = Eigen::Matrix<S, 2, 3>;

enum class CameraModel { KannalaBrandt4, Unified, ExtendedUnified, DoubleSphere, PinholeRadtan, Mei };

}  // namespace cs

namespace cs::models {

constexpr double kPi = 3.14159265358979323846;

template <class S>
constexpr S kEps = std::numeric_limits<S>::epsilon();

// Focal lengths and principal point: pixel = f * m + c for the model's normalised point m.
template <class S>
struct Intrinsics {
  S fx, fy, cx, cy;
  explicit Intrinsics(const double* p) : fx(S(p[0])), fy(S(p[1])), cx(S(p[2])), cy(S(p[3])) {}
  Vec2<S> toPixel(S mx, S my) const { return Vec2<S>(fx * mx + cx, fy * my + cy); }
  Vec2<S> toNormalized(const Vec2<S>& px) const { return Vec2<S>((px.x() - cx) / fx, (px.y() - cy) / fy); }
};

// Models of the form px = f * (x, y) / den(p) + c share their Jacobian:
// d(x/den)/dp = e_x/den - x * grad(den)/den^2.
template <class S>
void projectRational(const Intrinsics<S>& in, const Vec3<S>& p, S den, const Vec3<S>& gradDen, Vec2<S>& px,
                     Mat23<S>* J) {
  const S inv = S(1) / den;
  px = in.toPixel(p.x() * inv, p.y() * inv);
  if (!J) return;
  const S inv2 = inv * inv;
  J->row(0) = (-in.fx * p.x() * inv2) * gradDen.transpose();
  J->row(1) = (-in.fy * p.y() * inv2) * gradDen.transpose();
  (*J)(0, 0) += in.fx * inv;
  (*J)(1, 1) += in.fy * inv;
}

// The unified-family valid region is z > -w * d; w from the mirror parameter alpha
// (Usenko et al. 2018, eq. for UCM/EUCM/DS).
inline double unifiedW(double alpha) { return alpha > 0.5 ? (1.0 - alpha) / alpha : alpha / (1.0 - alpha); }

// Angle where the region z > -w * sqrt(beta (x^2+y^2) + z^2) ends: on the boundary
// cos(theta) = -w * sqrt(beta sin^2 + cos^2), i.e. tan(theta) = -sqrt(1-w^2) / (w sqrt(beta)).
inline double unifiedBoundaryAngle(double w, double beta) {
  const double wc = std::min(std::max(w, 0.0), 1.0);
  return std::atan2(std::sqrt(1.0 - wc * wc), -wc * std::sqrt(beta));
}

// ---------------------------------------------------------------------------------------
// Kannala-Brandt 4 (Kalibr pinhole + equidistant, OpenCV fisheye):
//   theta = atan2(r, z), theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8),
//   px = f * theta_d * (x, y) / r + c.   Works beyond 180 deg while theta < thetaMax.
template <class S>
struct KannalaBrandt4 {
  static constexpr CameraModel kModel = CameraModel::KannalaBrandt4;
  static constexpr const char* kName = "kannala-brandt4";
  static constexpr int kNumParams = 8;
  static constexpr const char* kParamNames[kNumParams] = {"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"};
  static constexpr int kDistortionParams = 4;
  static constexpr const char* kKalibrModel = "pinhole";
  static constexpr const char* kKalibrDistortion = "equidistant";
  template <class Fail>
  static void checkParams(const double*, Fail&&) {}  // any polynomial: thetaMax bounds it
  Intrinsics<S> in;
  S k1, k2, k3, k4;
  S thetaMax;   // first angle where theta_d stops increasing (or pi)
  S radiusMax;  // theta_d(thetaMax): the image of the valid region is rd < radiusMax

  explicit KannalaBrandt4(const double* p) : in(p), k1(S(p[4])), k2(S(p[5])), k3(S(p[6])), k4(S(p[7])) {
    const double tm = turningAngle(p[4], p[5], p[6], p[7]);
    thetaMax = S(tm);
    radiusMax = S(tm * (1 + tm * tm * (p[4] + tm * tm * (p[5] + tm * tm * (p[6] + tm * tm * p[7])))));
  }

  S distort(S th) const {
    const S t2 = th * th;
    return th * (S(1) + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))));
  }
  S distortDerivative(S th) const {
    const S t2 = th * th;
    return S(1) + t2 * (S(3) * k1 + t2 * (S(5) * k2 + t2 * (S(7) * k3 + t2 * S(9) * k4)));
  }

  // First theta in (0, pi] with d theta_d / d theta <= 0, else pi. The derivative is a
  // quartic in theta^2; sampling finely and bisecting the first sign change is exact
  // enough and needs no polynomial root finder.
  static double turningAngle(double c1, double c2, double c3, double c4) {
    auto slope = [&](double th) {
      const double t2 = th * th;
      return 1 + t2 * (3 * c1 + t2 * (5 * c2 + t2 * (7 * c3 + t2 * 9 * c4)));
    };
    constexpr int kSamples = 128;
    double prev = 0;
    for (int i = 1; i <= kSamples; ++i) {
      const double th = kPi * i / kSamples;
      if (slope(th) > 0) {
        prev = th;
        continue;
      }
      double lo = prev, hi = th;
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        (slope(mid) > 0 ? lo : hi) = mid;
      }
      return lo;
    }
    return kPi;
  }

  double maxAngle() const { return double(thetaMax); }
  std::array<double, 2> precomputed() const { return {double(thetaMax), double(radiusMax)}; }

  bool validPoint(const Vec3<S>& p) const {
    const S r = std::sqrt(p.x() * p.x() + p.y() * p.y());
    return (r > 0 || p.z() > 0) && std::atan2(r, p.z()) < thetaMax;
  }

  bool project(const Vec3<S>& p, Vec2<S>& px, Mat23<S>* J = nullptr) const {
    const S x = p.x(), y = p.y(), z = p.z();
    const S r2 = x * x + y * y;
    const S rho2 = r2 + z * z;
    if (!(rho2 > 0)) return false;
    const S r = std::sqrt(r2);
    const S th = std::atan2(r, z);
    if (!(th < thetaMax)) return false;
    // s = theta_d / r; on the axis its limit is 1/z (theta ~ r/z, theta_d ~ theta).
    const S s = r > 0 ? distort(th) / r : S(1) / z;
    px = in.toPixel(s * x, s * y);
    if (!J) return true;
    // ds/dr = r * A and ds/dz = B with A = (theta_d' z / rho^2 - s) / r^2, B = -theta_d' / rho^2.
    // Near the axis A loses all digits to cancellation; its limit 2 (k1 - 1/3) / z^3
    // (from the series of s in r/z) is then exact to rounding.
    const S dd = distortDerivative(th);
    const bool nearAxis = z > 0 && r2 < kEps<S> * rho2;
    const S A = nearAxis ? S(2) * (k1 - S(1) / S(3)) / (z * z * z) : (dd * z / rho2 - s) / r2;
    const S B = -dd / rho2;
    *J << in.fx * (s + x * x * A), in.fx * x * y * A, in.fx * x * B,  //
        in.fy * x * y * A, in.fy * (s + y * y * A), in.fy * y * B;
    return true;
  }

  bool unproject(const Vec2<S>& px, Vec3<S>& ray) const {
    const Vec2<S> m = in.toNormalized(px);
    const S rd = m.norm();
    if (!(rd < radiusMax)) return false;  // also rejects NaN
    if (rd == 0) {
      ray = Vec3<S>(0, 0, 1);
      return true;
    }
    const S th = solveTheta(rd);
    const S sinOverRd = std::sin(th) / rd;
    ray = Vec3<S>(m.x() * sinOverRd, m.y() * sinOverRd, std::cos(th));
    return true;
  }

  // theta with theta_d(theta) = rd, 0 < rd < radiusMax. Newton from theta = rd (exact
  // without distortion), kept inside the bracket [lo, hi] that the monotone theta_d
  // gives; a step leaving the bracket is replaced by bisection, so it always converges.
  S solveTheta(S rd) const {
    S lo = 0, hi = thetaMax;
    S th = rd < hi ? rd : S(0.5) * hi;
    for (int it = 0; it < 60; ++it) {
      const S f = distort(th) - rd;
      if (f == 0) break;
      (f < 0 ? lo : hi) = th;
      S next = th - f / distortDerivative(th);
      if (!(next > lo && next < hi)) next = S(0.5) * (lo + hi);
      const S step = std::abs(next - th);
      th = next;
      if (step <= S(4) * kEps<S> * th) break;
    }
    return th;
  }
};

// ---------------------------------------------------------------------------------------
// Unified camera model (Kalibr omni without distortion): px = f * (x, y) / (z + xi |p|) + c.
// Valid region z > -w |p| with w = xi (xi <= 1) or 1/xi (xi > 1).
template <class S>
struct Unified {
  static constexpr CameraModel kModel = CameraModel::Unified;
  static constexpr const char* kName = "unified";
  static constexpr int kNumParams = 5;
  static constexpr const char* kParamNames[kNumParams] = {"fx", "fy", "cx", "cy", "xi"};
  static constexpr int kDistortionParams = 0;
  static constexpr const char* kKalibrModel = "omni";
  static constexpr const char* kKalibrDistortion = "none";
  template <class Fail>
  static void checkParams(const double* p, Fail&& fail) {
    if (p[4] < 0) fail(4, "is negative");
  }
  Intrinsics<S> in;
  S xi;
  S w;

  explicit Unified(const double* p) : in(p), xi(S(p[4])), w(S(p[4] <= 1 ? p[4] : 1.0 / p[4])) {}

  double maxAngle() const { return unifiedBoundaryAngle(double(w), 1.0); }
  std::array<double, 2> precomputed() const { return {double(w), 0.0}; }

  bool validPoint(const Vec3<S>& p) const { return p.z() > -w * p.norm(); }

  bool project(const Vec3<S>& p, Vec2<S>& px, Mat23<S>* J = nullptr) const {
    const S d = p.norm();
    if (!(p.z() > -w * d)) return false;
    const S den = p.z() + xi * d;
    if (!(den > 0)) return false;
    const Vec3<S> gradDen = (xi / d) * p + Vec3<S>(0, 0, 1);
    projectRational(in, p, den, gradDen, px, J);
    return true;
  }

  // Closed form: the ray is factor * (mx, my, 1) - (0, 0, xi) with
  // factor = (xi + sqrt(1 + (1 - xi^2) r^2)) / (1 + r^2).
  bool unproject(const Vec2<S>& px, Vec3<S>& ray) const {
    const Vec2<S> m = in.toNormalized(px);
    const S r2 = m.squaredNorm();
    const S disc = S(1) + (S(1) - xi * xi) * r2;
    if (!(disc >= 0)) return false;
    const S factor = (xi + std::sqrt(disc)) / (S(1) + r2);
    ray = Vec3<S>(factor * m.x(), factor * m.y(), factor - xi).normalized();
    return validPoint(ray);
  }
};

// ---------------------------------------------------------------------------------------
// Extended unified camera model: d = sqrt(beta (x^2 + y^2) + z^2),
// px = f * (x, y) / (alpha d + (1 - alpha) z) + c. Valid region z > -w d.
template <class S>
struct ExtendedUnified {
  static constexpr CameraModel kModel = CameraModel::ExtendedUnified;
  static constexpr const char* kName = "extended-unified";
  static constexpr int kNumParams = 6;
  static constexpr const char* kParamNames[kNumParams] = {"fx", "fy", "cx", "cy", "alpha", "beta"};
  static constexpr int kDistortionParams = 0;
  static constexpr const char* kKalibrModel = "eucm";
  static constexpr const char* kKalibrDistortion = "none";
  template <class Fail>
  static void checkParams(const double* p, Fail&& fail) {
    if (p[4] < 0 || p[4] > 1) fail(4, "is outside [0, 1]");
    if (p[5] <= 0) fail(5, "is not positive");
  }
  Intrinsics<S> in;
  S alpha, beta;
  S w;

  explicit ExtendedUnified(const double* p) : in(p), alpha(S(p[4])), beta(S(p[5])), w(S(unifiedW(p[4]))) {}

  double maxAngle() const { return unifiedBoundaryAngle(double(w), double(beta)); }
  std::array<double, 2> precomputed() const { return {double(w), 0.0}; }

  S distance(const Vec3<S>& p) const { return std::sqrt(beta * (p.x() * p.x() + p.y() * p.y()) + p.z() * p.z()); }

  bool validPoint(const Vec3<S>& p) const { return p.z() > -w * distance(p); }

  bool project(const Vec3<S>& p, Vec2<S>& px, Mat23<S>* J = nullptr) const {
    const S d = distance(p);
    if (!(p.z() > -w * d)) return false;
    const S den = alpha * d + (S(1) - alpha) * p.z();
    if (!(den > 0)) return false;
    const Vec3<S> gradD = Vec3<S>(beta * p.x(), beta * p.y(), p.z()) / d;
    const Vec3<S> gradDen = alpha * gradD + Vec3<S>(0, 0, S(1) - alpha);
    projectRational(in, p, den, gradDen, px, J);
    return true;
  }

  // Closed form (Usenko et al. 2018): mz = (1 - beta alpha^2 r^2) /
  // (alpha sqrt(1 - (2 alpha - 1) beta r^2) + 1 - alpha); ray = normalize(mx, my, mz).
  bool unproject(const Vec2<S>& px, Vec3<S>& ray) const {
    const Vec2<S> m = in.toNormalized(px);
    const S r2 = m.squaredNorm();
    const S disc = S(1) - (S(2) * alpha - S(1)) * beta * r2;
    if (!(disc >= 0)) return false;
    const S mz = (S(1) - beta * alpha * alpha * r2) / (alpha * std::sqrt(disc) + S(1) - alpha);
    ray = Vec3<S>(m.x(), m.y(), mz).normalized();
    return validPoint(ray);
  }
};

// ---------------------------------------------------------------------------------------
// Double sphere model: d1 = |p|, k = xi d1 + z, d2 = sqrt(x^2 + y^2 + k^2),
// px = f * (x, y) / (alpha d2 + (1 - alpha) k) + c. Valid region z > -w2 d1.
template <class S>
struct DoubleSphere {
  static constexpr CameraModel kModel = CameraModel::DoubleSphere;
  static constexpr const char* kName = "double-sphere";
  static constexpr int kNumParams = 6;
  static constexpr const char* kParamNames[kNumParams] = {"fx", "fy", "cx", "cy", "xi", "alpha"};
  static constexpr int kDistortionParams = 0;
  static constexpr const char* kKalibrModel = "ds";
  static constexpr const char* kKalibrDistortion = "none";
  // Calibrations commonly have slightly negative xi; at xi <= -1 the second sphere
  // degenerates (the valid-region bound divides by zero).
  template <class Fail>
  static void checkParams(const double* p, Fail&& fail) {
    if (p[4] <= -1) fail(4, "is not greater than -1");
    if (p[5] < 0 || p[5] > 1) fail(5, "is outside [0, 1]");
  }
  Intrinsics<S> in;
  S xi, alpha;
  S w2;

  explicit DoubleSphere(const double* p) : in(p), xi(S(p[4])), alpha(S(p[5])), w2(S(boundaryW(p[4], p[5]))) {}

  // w2 = (w1 + xi) / sqrt(2 w1 xi + xi^2 + 1) (Usenko et al. 2018).
  static double boundaryW(double xi, double alpha) {
    const double w1 = unifiedW(alpha);
    return (w1 + xi) / std::sqrt(2 * w1 * xi + xi * xi + 1);
  }

  double maxAngle() const { return unifiedBoundaryAngle(double(w2), 1.0); }
  std::array<double, 2> precomputed() const { return {double(w2), 0.0}; }

  bool validPoint(const Vec3<S>& p) const { return p.z() > -w2 * p.norm(); }

  bool project(const Vec3<S>& p, Vec2<S>& px, Mat23<S>* J = nullptr) const {
    const S d1 = p.norm();
    if (!(p.z() > -w2 * d1)) return false;
    const S k = xi * d1 + p.z();
    const S d2 = std::sqrt(p.x() * p.x() + p.y() * p.y() + k * k);
    const S den = alpha * d2 + (S(1) - alpha) * k;
    if (!(den > 0)) return false;
    const Vec3<S> gradK = (xi / d1) * p + Vec3<S>(0, 0, 1);
    const Vec3<S> gradD2 = (Vec3<S>(p.x(), p.y(), 0) + k * gradK) / d2;
    const Vec3<S> gradDen = alpha * gradD2 + (S(1) - alpha) * gradK;
    projectRational(in, p, den, gradDen, px, J);
    return true;
  }

  // Closed form (Usenko et al. 2018): mz = (1 - alpha^2 r^2) / (alpha sqrt(1 - (2 alpha - 1) r^2)
  // + 1 - alpha); ray = (mz xi + sqrt(mz^2 + (1 - xi^2) r^2)) / (mz^2 + r^2) * (mx, my, mz) - (0, 0, xi).
  bool unproject(const Vec2<S>& px, Vec3<S>& ray) const {
    const Vec2<S> m = in.toNormalized(px);
    const S r2 = m.squaredNorm();
    const S disc1 = S(1) - (S(2) * alpha - S(1)) * r2;
    if (!(disc1 >= 0)) return false;
    const S mz = (S(1) - alpha * alpha * r2) / (alpha * std::sqrt(disc1) + S(1) - alpha);
    const S disc2 = mz * mz + (S(1) - xi * xi) * r2;
    if (!(disc2 >= 0)) return false;
    const S factor = (mz * xi + std::sqrt(disc2)) / (mz * mz + r2);
    ray = Vec3<S>(factor * m.x(), factor * m.y(), factor * mz - xi).normalized();
    return validPoint(ray);
  }
};

// ---------------------------------------------------------------------------------------
// Radial-tangential distortion of a normalised point (Kalibr radtan, OpenCV k1 k2 p1 p2),
// shared by the pinhole and the MEI model.
template <class S>
struct Radtan {
  static constexpr int kNewtonIterations = 20;
  S k1, k2, p1, p2;

  explicit Radtan(const double* k) : k1(S(k[0])), k2(S(k[1])), p1(S(k[2])), p2(S(k[3])) {}

  // Distorted point and, optionally, its 2x2 Jacobian d(distorted)/d(n).
  Vec2<S> distort(const Vec2<S>& n, Eigen::Matrix<S, 2, 2>* Jd = nullptr) const {
    const S x = n.x(), y = n.y();
    const S r2 = x * x + y * y;
    const S radial = S(1) + r2 * (k1 + r2 * k2);
    const Vec2<S> out(x * radial + S(2) * p1 * x * y + p2 * (r2 + S(2) * x * x),
                      y * radial + p1 * (r2 + S(2) * y * y) + S(2) * p2 * x * y);
    if (Jd) {
      const S dRadial = S(2) * (k1 + S(2) * k2 * r2);                   // d(radial)/d(x) = dRadial * x
      *Jd << radial + x * x * dRadial + S(2) * p1 * y + S(6) * p2 * x,  //
          x * y * dRadial + S(2) * p1 * x + S(2) * p2 * y,              //
          x * y * dRadial + S(2) * p1 * x + S(2) * p2 * y,              //
          radial + y * y * dRadial + S(6) * p1 * y + S(2) * p2 * x;
    }
    return out;
  }

  // Newton on distort(n) = m from n = start (the pinhole model starts at m, which converges
  // in a few steps for real lenses). False when the iteration ends without reaching the
  // target (outside the region where the distortion is invertible).
  bool undistort(const Vec2<S>& m, const Vec2<S>& start, Vec2<S>& n) const {
    if (!m.allFinite() || !start.allFinite()) return false;
    n = start;
    Eigen::Matrix<S, 2, 2> Jd;
    for (int it = 0; it < kNewtonIterations; ++it) {
      const Vec2<S> residual = distort(n, &Jd) - m;
      const S det = Jd(0, 0) * Jd(1, 1) - Jd(0, 1) * Jd(1, 0);
      if (!(std::abs(det) > kEps<S>)) return false;
      // 2x2 solve by the adjugate (Eigen/Core has no inverse()).
      const Vec2<S> step((Jd(1, 1) * residual.x() - Jd(0, 1) * residual.y()) / det,
                         (Jd(0, 0) * residual.y() - Jd(1, 0) * residual.x()) / det);
      n -= step;
      if (step.norm() <= S(16) * kEps<S> * (S(1) + n.norm())) break;
    }
    const S accepted = std::sqrt(kEps<S>) * (S(1) + m.norm());
    return (distort(n) - m).norm() <= accepted;
  }

  // The undistorted radius r in [0, rMax] whose radial image r (1 + k1 r^2 + k2 r^4) is rd:
  // Newton kept inside the bracket the monotone radial part gives, bisecting a step that
  // leaves it (as KannalaBrandt4::solveTheta). A start for undistort() far from the axis,
  // where Newton from m would need many steps.
  S solveRadius(S rd, S rMax) const {
    S lo = 0, hi = rMax;
    S r = rd < hi ? rd : S(0.5) * hi;
    for (int it = 0; it < 60; ++it) {
      const S r2 = r * r;
      const S f = r * (S(1) + r2 * (k1 + r2 * k2)) - rd;
      if (f == 0) break;
      (f < 0 ? lo : hi) = r;
      S next = r - f / (S(1) + r2 * (S(3) * k1 + S(5) * k2 * r2));
      if (!(next > lo && next < hi)) next = S(0.5) * (lo + hi);
      const S step = std::abs(next - r);
      r = next;
      if (step <= S(4) * kEps<S> * r) break;
    }
    return r;
  }

  // The first undistorted radius where the radial part r (1 + k1 r^2 + k2 r^4) stops
  // increasing: the smallest positive root s = r^2 of 1 + 3 k1 s + 5 k2 s^2, else
  // kUnbounded (finite, so that float shaders compare with it safely).
  static constexpr double kUnbounded = 1e6;
  static double turningRadius(double c1, double c2) {
    double s = -1;
    if (c2 == 0) {
      if (c1 < 0) s = -1.0 / (3 * c1);
    } else {
      const double disc = 9 * c1 * c1 - 20 * c2;
      if (disc >= 0) {
        const double q = std::sqrt(disc);
        const double a = (-3 * c1 - q) / (10 * c2), b = (-3 * c1 + q) / (10 * c2);
        const double lo = std::min(a, b), hi = std::max(a, b);
        s = lo > 0 ? lo : hi;
      }
    }
    return s > 0 ? std::min(std::sqrt(s), kUnbounded) : kUnbounded;
  }
};

// ---------------------------------------------------------------------------------------
// Pinhole with radial-tangential distortion (Kalibr radtan, OpenCV k1 k2 p1 p2) on the
// normalised point n = (x, y) / z. Valid for z > 1e-6 |p| (in front of the camera).
template <class S>
struct PinholeRadtan {
  static constexpr CameraModel kModel = CameraModel::PinholeRadtan;
  static constexpr const char* kName = "pinhole-radtan";
  static constexpr int kNumParams = 8;
  static constexpr const char* kParamNames[kNumParams] = {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"};
  static constexpr int kDistortionParams = 4;
  static constexpr const char* kKalibrModel = "pinhole";
  static constexpr const char* kKalibrDistortion = "radtan";
  template <class Fail>
  static void checkParams(const double*, Fail&&) {}
  Intrinsics<S> in;
  Radtan<S> rt;
  int width, height;  // maxAngle() is the angle of the widest image corner

  PinholeRadtan(const double* p, int w, int h) : in(p), rt(p + 4), width(w), height(h) {}

  std::array<double, 2> precomputed() const { return {0.0, 0.0}; }

  bool validPoint(const Vec3<S>& p) const { return p.z() > S(1e-6) * p.norm(); }

  bool project(const Vec3<S>& p, Vec2<S>& px, Mat23<S>* J = nullptr) const {
    if (!validPoint(p)) return false;
    const S iz = S(1) / p.z();
    const Vec2<S> n(p.x() * iz, p.y() * iz);
    Eigen::Matrix<S, 2, 2> Jd;
    const Vec2<S> md = rt.distort(n, J ? &Jd : nullptr);
    px = in.toPixel(md.x(), md.y());
    if (!J) return true;
    Mat23<S> Jn;  // d(n)/d(p)
    Jn << iz, 0, -n.x() * iz, 0, iz, -n.y() * iz;
    *J = Eigen::DiagonalMatrix<S, 2>(in.fx, in.fy) * Jd * Jn;
    return true;
  }

  bool unproject(const Vec2<S>& px, Vec3<S>& ray) const {
    const Vec2<S> m = in.toNormalized(px);
    Vec2<S> n;
    if (!rt.undistort(m, m, n)) return false;
    ray = Vec3<S>(n.x(), n.y(), S(1)).normalized();
    return true;
  }

  // The widest ray through an image corner; pi/2 when a corner does not unproject.
  double maxAngle() const {
    const double xs[2] = {-0.5, width - 0.5}, ys[2] = {-0.5, height - 0.5};
    double widest = 0;
    for (double cx : xs) {
      for (double cy : ys) {
        Vec3<S> ray;
        if (!unproject(Vec2<S>(S(cx), S(cy)), ray)) return kPi / 2;
        widest = std::max(widest, std::acos(std::min(1.0, double(ray.z()))));
      }
    }
    return widest;
  }
};

// ---------------------------------------------------------------------------------------
// MEI model (Mei & Rives 2007; Kalibr omni + radtan, camodocal MEI): the unified
// projection m = (x, y) / (z + xi |p|), then radial-tangential distortion of m, then
// px = f * distort(m) + c. Params [fx fy cx cy xi k1 k2 p1 p2].
// Valid region: the unified one (z > -w |p|) where also |m| < rMax, the radius where the
// radial distortion stops increasing, so that every valid pixel has one ray.
template <class S>
struct Mei {
  static constexpr CameraModel kModel = CameraModel::Mei;
  static constexpr const char* kName = "mei";
  static constexpr int kNumParams = 9;
  static constexpr const char* kParamNames[kNumParams] = {"fx", "fy", "cx", "cy", "xi", "k1", "k2", "p1", "p2"};
  static constexpr int kDistortionParams = 4;
  static constexpr const char* kKalibrModel = "omni";
  static constexpr const char* kKalibrDistortion = "radtan";
  template <class Fail>
  static void checkParams(const double* p, Fail&& fail) {
    if (p[4] < 0) fail(4, "is negative");
  }
  Intrinsics<S> in;
  S xi;
  Radtan<S> rt;
  S w;     // the unified valid region z > -w |p|
  S rMax;  // undistorted radius bound (Radtan::turningRadius)

  explicit Mei(const double* p)
      : in(p),
        xi(S(p[4])),
        rt(p + 5),
        w(S(p[4] <= 1 ? p[4] : 1.0 / p[4])),
        rMax(S(Radtan<double>::turningRadius(p[5], p[6]))) {}

  std::array<double, 2> precomputed() const { return {double(w), double(rMax)}; }

  // The unified ray of undistorted radius r makes the angle atan2(f r, f - xi) with the
  // axis, f = (xi + sqrt(1 + (1 - xi^2) r^2)) / (1 + r^2); it grows with r up to the
  // unified boundary.
  double maxAngle() const {
    const double x = double(xi), r = double(rMax);
    const double boundary = unifiedBoundaryAngle(double(w), 1.0);
    const double disc = 1 + (1 - x * x) * r * r;
    if (!(disc >= 0)) return boundary;
    const double f = (x + std::sqrt(disc)) / (1 + r * r);
    return std::min(boundary, std::atan2(f * r, f - x));
  }

  bool validPoint(const Vec3<S>& p) const {
    const S d = p.norm();
    if (!(p.z() > -w * d)) return false;
    const S den = p.z() + xi * d;
    if (!(den > 0)) return false;
    const S inv = S(1) / den;
    return Vec2<S>(p.x() * inv, p.y() * inv).norm() < rMax;
  }

  bool project(const Vec3<S>& p, Vec2<S>& px, Mat23<S>* J = nullptr) const {
    const S d = p.norm();
    if (!(p.z() > -w * d)) return false;
    const S den = p.z() + xi * d;
    if (!(den > 0)) return false;
    const S inv = S(1) / den;
    const Vec2<S> m(p.x() * inv, p.y() * inv);
    if (!(m.norm() < rMax)) return false;
    Eigen::Matrix<S, 2, 2> Jd;
    const Vec2<S> md = rt.distort(m, J ? &Jd : nullptr);
    px = in.toPixel(md.x(), md.y());
    if (!J) return true;
    // d(m)/d(p) = (e_xy - m grad(den)^T) / den, grad(den) = xi p / d + e_z.
    const Vec3<S> gradDen = (xi / d) * p + Vec3<S>(0, 0, 1);
    Mat23<S> Jm;
    Jm.row(0) = (-m.x() * inv) * gradDen.transpose();
    Jm.row(1) = (-m.y() * inv) * gradDen.transpose();
    Jm(0, 0) += inv;
    Jm(1, 1) += inv;
    *J = Eigen::DiagonalMatrix<S, 2>(in.fx, in.fy) * Jd * Jm;
    return true;
  }

  // Undistort by Newton (Radtan::undistort) from the radial-only solution, then the unified
  // closed form ray = factor * (mx, my, 1) - (0, 0, xi), factor = (xi + sqrt(1 + (1 - xi^2)
  // r^2)) / (1 + r^2).
  bool unproject(const Vec2<S>& px, Vec3<S>& ray) const {
    const Vec2<S> md = in.toNormalized(px);
    if (!md.allFinite()) return false;
    const S rd = md.norm();
    const Vec2<S> start = rd > 0 ? Vec2<S>(md * (rt.solveRadius(rd, rMax) / rd)) : md;
    Vec2<S> m;
    if (!rt.undistort(md, start, m)) return false;
    if (!(m.norm() < rMax)) return false;
    const S r2 = m.squaredNorm();
    const S disc = S(1) + (S(1) - xi * xi) * r2;
    if (!(disc >= 0)) return false;
    const S factor = (xi + std::sqrt(disc)) / (S(1) + r2);
    ray = Vec3<S>(factor * m.x(), factor * m.y(), factor - xi).normalized();
    return ray.z() > -w * ray.norm();
  }
};

// One of the models, in CameraModel's order (AnyModel<S>::index() == int(model)).
template <class S>
using AnyModel =
    std::variant<KannalaBrandt4<S>, Unified<S>, ExtendedUnified<S>, DoubleSphere<S>, PinholeRadtan<S>, Mei<S>>;

// The model type M as a value, for visitors of the model types: decltype(tag)::type.
template <class M>
struct ModelTag {
  using type = M;
};

template <class... M, size_t... I>
constexpr bool inCameraModelOrder(std::variant<M...>*, std::index_sequence<I...>) {
  return ((int(M::kModel) == int(I)) && ...);
}
static_assert(inCameraModelOrder(static_cast<AnyModel<double>*>(nullptr),
                                 std::make_index_sequence<std::variant_size_v<AnyModel<double>>>{}),
              "AnyModel<S>::index() == int(model)");

template <class F, class... M>
bool visitModelTypeAmong(CameraModel model, F& f, std::variant<M...>*) {
  return ((model == M::kModel ? (f(ModelTag<M>{}), true) : false) || ...);
}

// Calls f(ModelTag<M>{}) for the model type M (in scalar S) of `model`; false, without
// calling f, for a value that is no CameraModel. The one place that maps a CameraModel to its
// model: everything per model is read through here or through AnyModel.
template <class S = double, class F>
bool visitModelType(CameraModel model, F&& f) {
  return visitModelTypeAmong(model, f, static_cast<AnyModel<S>*>(nullptr));
}

template <class F, class... M>
void forEachModelTypeAmong(F& f, std::variant<M...>*) {
  (f(ModelTag<M>{}), ...);
}

// Calls f(ModelTag<M>{}) for every model type M (in scalar S), in CameraModel's order.
template <class S = double, class F>
void forEachModelType(F&& f) {
  forEachModelTypeAmong(f, static_cast<AnyModel<S>*>(nullptr));
}

// Number of entries of Camera::params for a model; -1 for no model.
inline int paramCount(CameraModel model) {
  int n = -1;
  visitModelType(model, [&](auto tag) { n = decltype(tag)::type::kNumParams; });
  return n;
}

// The model `model` in scalar S from params [fx fy cx cy extra...], which must have
// paramCount(model) entries (BuiltCamera checks it); width and height are the image's.
template <class S>
AnyModel<S> makeModel(CameraModel model, const double* params, int width, int height) {
  std::optional<AnyModel<S>> built;
  visitModelType<S>(model, [&](auto tag) {
    using M = typename decltype(tag)::type;
    if constexpr (std::is_constructible_v<M, const double*, int, int>)
      built.emplace(M(params, width, height));
    else
      built.emplace(M(params));
  });
  // No model: a Kannala-Brandt, as before the models were visited (BuiltCamera refuses it first).
  return built ? std::move(*built) : AnyModel<S>(KannalaBrandt4<S>(params));
}

}  // namespace cs::models

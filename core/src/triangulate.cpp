#include "curvestereo/triangulate.hpp"

#include <cmath>
#include <limits>

namespace cs {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

double triangulateRadial(const Camera& cam0, const Eigen::Vector3d& tPrime, const Vec2<double>& x,
                         const Vec2<double>& w) {
  Vec3<double> d0, d1;
  if (!cam0.unproject(x, d0) || !cam0.unproject(Vec2<double>(x + w), d1)) return kNaN;
  // Closest points of the rays r0(a) = a d0 and r1(b) = c1 + b d1, c1 = -t'. Solve the
  // 2x2 normal equations; parallel or diverging rays mean the point is at infinity.
  const Eigen::Vector3d c1 = -tPrime;
  double k = d0.dot(d1);
  double det = 1.0 - k * k;
  if (det < 1e-14) return kInf;
  double e0 = d0.dot(c1), e1 = d1.dot(c1);
  double a = (e0 - k * e1) / det;
  double b = (k * e0 - e1) / det;
  if (!(a > 0) || !(b > 0)) return kInf;
  return a;
}

bool warpFromDepth(const Camera& cam0, const Eigen::Vector3d& tPrime, const Vec2<double>& x, double radial,
                   Vec2<double>& w) {
  Vec3<double> d0;
  if (!cam0.unproject(x, d0)) return false;
  // At infinite depth the second view sees the same direction.
  Vec3<double> X = std::isinf(radial) ? d0 : Vec3<double>(radial * d0 + tPrime);
  Vec2<double> px;
  if (!cam0.project(X, px)) return false;
  w = px - x;
  return true;
}

DepthMaps triangulate(const Camera& cam0, const Eigen::Vector3d& tPrime, const FlowImage& w,
                      const ImageU8& valid) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  DepthMaps out;
  out.radial = ImageF(w.width, w.height, nan);
  out.z = ImageF(w.width, w.height, nan);
  out.points = Image<Point3f>(w.width, w.height, Point3f{nan, nan, nan});
  for (int y = 0; y < w.height; ++y)
    for (int x = 0; x < w.width; ++x) {
      if (!valid(x, y)) continue;
      Vec2<double> px(x, y), wx(w(x, y).x, w(x, y).y);
      double r = triangulateRadial(cam0, tPrime, px, wx);
      Vec3<double> ray;
      if (std::isnan(r) || !cam0.unproject(px, ray)) continue;
      out.radial(x, y) = float(r);
      out.z(x, y) = float(r * ray.z());
      if (std::isfinite(r)) out.points(x, y) = {float(r * ray.x()), float(r * ray.y()), float(r * ray.z())};
    }
  return out;
}

}  // namespace cs

#include "curvestereo/triangulate.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <limits>

namespace cs {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

double triangulateRadial(const BuiltCamera& cam0, const Eigen::Vector3d& tPrime, const Vec2<double>& x,
                         const Vec2<double>& w) {
  Vec3<double> d0, d1;
  if (!cam0.unproject(x, d0) || !cam0.unproject(Vec2<double>(x + w), d1)) return kNaN;
  // The point a d0 = c1 + b d1 with c1 = -t'. Crossing with d1 gives
  // a (d0 x d1) = c1 x d1, solved in least squares. Cross products keep the small
  // parallax angles of distant points accurate, where 1 - (d0 . d1)^2 would cancel.
  const Eigen::Vector3d c1 = -tPrime;
  const Eigen::Vector3d n = d0.cross(d1);
  const double n2 = n.squaredNorm();
  if (n2 < 1e-24) return kInf;
  const double a = c1.cross(d1).dot(n) / n2;
  const double b = c1.cross(d0).dot(n) / n2;  // crossing with d0: b (d0 x d1) = c1 x d0
  // Both rays must point forward to the point: a > 0 along ray 0, and the point seen
  // from camera 1 in front of it (b > 0 along ray 1).
  if (!(a > 0) || !(b > 0)) return kInf;
  return a;
}

bool warpFromDepth(const BuiltCamera& cam0, const Eigen::Vector3d& tPrime, const Vec2<double>& x, double radial,
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

DepthMaps triangulate(const Camera& camera0, const Eigen::Vector3d& tPrime, const FlowImage& w, const ImageU8& valid) {
  const BuiltCamera cam0(camera0);
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

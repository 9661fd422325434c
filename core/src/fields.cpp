#include "curvestereo/fields.hpp"

#include <cmath>

namespace cs {

namespace {

constexpr double kDegToRad = M_PI / 180.0;

// Angle between the ray and the optical axis (z).
double offAxisAngle(const Vec3<double>& ray) { return std::atan2(ray.head<2>().norm(), ray.z()); }

// Angle between the ray and the baseline line (either direction): depth along rays near
// the epipoles is unobservable.
double angleToBaseline(const Vec3<double>& ray, const Eigen::Vector3d& baselineDir) {
  double c = std::abs(ray.dot(baselineDir));
  return std::acos(std::min(1.0, c));
}

}  // namespace

PixelFields fieldsAtPixel(const BuiltCamera& cam0, const BuiltCamera& cam1, const Eigen::Matrix3d& R,
                          const Eigen::Vector3d& t, const FieldOptions& opt, int x, int y) {
  const Eigen::Vector3d tPrime = R.transpose() * t;
  PixelFields f;
  Vec2<double> px(x, y);
  Vec3<double> ray;
  if (!cam0.unproject(px, ray)) return f;
  const double halfFov = 0.5 * opt.maxFovDeg * kDegToRad;
  if (opt.maxFovDeg > 0 && offAxisAngle(ray) > halfFov) return f;
  if (angleToBaseline(ray, tPrime.normalized()) < opt.epipoleDeg * kDegToRad) return f;

  // Calibration: where the same ray lands in image 1 (rotation and intrinsics only). The
  // field of view holds for camera 1 too: when the cameras are not parallel, a crescent
  // of camera 0's rim lies outside camera 1's, and image 1 there is whatever surrounds its
  // image circle (black on the renders). Solved, those pixels matched that surround and
  // pulled their neighbours with them (docs/accuracy.md "How realtime was chosen": the rim).
  const Vec3<double> ray1 = R * ray;
  if (opt.maxFovDeg > 0 && offAxisAngle(ray1) > halfFov) return f;
  Vec2<double> px1;
  if (!cam1.project(ray1, px1) || !cam1.inImage(px1)) return f;

  // Trajectory: image motion of the point as its inverse depth grows, d(pi0)/dX . t'.
  Vec2<double> proj;
  Mat23<double> J;
  if (!cam0.project(ray, proj, &J)) return f;
  Vec2<double> tangent = J * tPrime;
  double n = tangent.norm();
  if (!(n > 1e-12)) return f;
  tangent /= n;

  f.valid = true;
  f.calibration = {float(px1.x() - x), float(px1.y() - y)};
  f.trajectory = {float(tangent.x()), float(tangent.y())};
  return f;
}

RigFields computeFields(const Camera& cam0, const Camera& cam1, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                        const FieldOptions& options) {
  const BuiltCamera built0(cam0), built1(cam1);
  RigFields out;
  out.mask = ImageU8(cam0.width, cam0.height, 0);
  out.calibration = FlowImage(cam0.width, cam0.height);
  out.trajectory = FlowImage(cam0.width, cam0.height);
  for (int y = 0; y < cam0.height; ++y)
    for (int x = 0; x < cam0.width; ++x) {
      PixelFields f = fieldsAtPixel(built0, built1, R, t, options, x, y);
      out.mask(x, y) = f.valid ? 1 : 0;
      out.calibration(x, y) = f.calibration;
      out.trajectory(x, y) = f.trajectory;
    }
  return out;
}

}  // namespace cs

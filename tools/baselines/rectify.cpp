#include "baselines/rectify.hpp"
#include "baselines/methods.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "curvestereo/triangulate.hpp"

namespace cs::baselines {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

Rectification makeRectification(const Rig& rig, double fovDeg, int size) {
  if (!(fovDeg > 0 && fovDeg < 179.9)) throw Error("rectification needs a field of view in (0, 180) degrees");
  if (size < 8) throw Error("rectified images must be at least 8 px wide");
  // Camera 1's centre in camera-0 coordinates.
  const Eigen::Vector3d c1 = -rig.R.transpose() * rig.t;
  const double B = c1.norm();
  if (!(B > 1e-9)) throw Error("rectification needs a non-zero baseline");
  const Eigen::Vector3d ex = c1 / B;
  Eigen::Vector3d ez = Eigen::Vector3d::UnitZ() - ex.z() * ex;
  Eigen::Vector3d ey;
  if (ez.norm() > 0.2) {
    ez.normalize();
    ey = ez.cross(ex);
  } else {
    // Baseline (nearly) along the optical axis: keep camera 0's y axis instead.
    ey = (Eigen::Vector3d::UnitY() - ex.y() * ex).normalized();
    ez = ex.cross(ey);
  }
  Rectification r;
  r.fovDeg = fovDeg;
  r.rot0.row(0) = ex.transpose();
  r.rot0.row(1) = ey.transpose();
  r.rot0.row(2) = ez.transpose();
  // X_rect1 = rot0 (X0 - c1) = rot0 R^T (X1 - t) - rot0 c1 = rot0 R^T X1.
  r.rot1 = r.rot0 * rig.R.transpose();
  const double f = 0.5 * size / std::tan(0.5 * fovDeg * kPi / 180.0);
  const double c = 0.5 * (size - 1);
  const Camera pin = Camera::pinholeRadtan(size, size, f, f, c, c);
  r.rectified.cam0 = pin;
  r.rectified.cam1 = pin;
  r.rectified.R = Eigen::Matrix3d::Identity();
  r.rectified.t = Eigen::Vector3d(-B, 0, 0);

  const float nan = std::numeric_limits<float>::quiet_NaN();
  r.map0 = FlowImage(size, size, Vec2f{nan, nan});
  r.map1 = FlowImage(size, size, Vec2f{nan, nan});
  const BuiltCamera pinhole(pin), cam0(rig.cam0), cam1(rig.cam1);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      Vec2<double> s;
      if (rectifiedToSource(pinhole, cam0, r.rot0, Vec2<double>(x, y), s)) r.map0(x, y) = {float(s.x()), float(s.y())};
      if (rectifiedToSource(pinhole, cam1, r.rot1, Vec2<double>(x, y), s)) r.map1(x, y) = {float(s.x()), float(s.y())};
    }
  return r;
}

bool rectifiedToSource(const BuiltCamera& pinhole, const BuiltCamera& cam, const Eigen::Matrix3d& rot,
                       const Vec2<double>& p, Vec2<double>& src) {
  Vec3<double> ray;
  if (!pinhole.unproject(p, ray)) return false;
  const Vec3<double> rc = rot.transpose() * ray;
  // Stay inside the one-to-one part of the lens model (rays up to maxAngle off axis).
  if (std::acos(std::min(1.0, std::max(-1.0, rc.z()))) > cam.maxAngle()) return false;
  if (!cam.project(rc, src)) return false;
  return cam.inImage(src);
}

bool sourceToRectified(const BuiltCamera& pinhole, const BuiltCamera& cam, const Eigen::Matrix3d& rot,
                       const Vec2<double>& src, Vec2<double>& p) {
  Vec3<double> ray;
  if (!cam.unproject(src, ray)) return false;
  const Vec3<double> rr = rot * ray;
  if (rr.z() <= 1e-9) return false;
  if (!pinhole.project(rr, p)) return false;
  return pinhole.inImage(p);
}

ImageF remap(const ImageF& img, const FlowImage& map, ImageU8* valid) {
  ImageF out(map.width, map.height, 0.f);
  if (valid) *valid = ImageU8(map.width, map.height, 0);
  for (size_t i = 0; i < map.size(); ++i) {
    const Vec2f m = map.data[i];
    if (!std::isfinite(m.x) || !std::isfinite(m.y)) continue;
    // Clamp-to-edge bilinear: map entries lie inside [-0.5, size - 0.5].
    const double x = std::min(std::max(double(m.x), 0.0), img.width - 1.0);
    const double y = std::min(std::max(double(m.y), 0.0), img.height - 1.0);
    const int x0 = std::min(int(x), img.width - 2 < 0 ? 0 : img.width - 2);
    const int y0 = std::min(int(y), img.height - 2 < 0 ? 0 : img.height - 2);
    const int x1 = std::min(x0 + 1, img.width - 1), y1 = std::min(y0 + 1, img.height - 1);
    const float fx = float(x - x0), fy = float(y - y0);
    out.data[i] =
        (1 - fy) * ((1 - fx) * img(x0, y0) + fx * img(x1, y0)) + fy * ((1 - fx) * img(x0, y1) + fx * img(x1, y1));
    if (valid) valid->data[i] = 1;
  }
  return out;
}

ImageF depthToSource(const Rectification& rect, const Camera& cam0, const FlowImage& rectWarp) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const BuiltCamera pin(rect.rectified.cam0), cam(cam0);
  const Eigen::Vector3d tpRect = rect.rectified.tPrime();
  // Only the horizontal component carries information on the rectified rig.
  ImageF du(rectWarp.width, rectWarp.height, nan);
  for (size_t i = 0; i < du.size(); ++i) du.data[i] = rectWarp.data[i].x;
  ImageF out(cam0.width, cam0.height, nan);
  for (int y = 0; y < cam0.height; ++y)
    for (int x = 0; x < cam0.width; ++x) {
      Vec2<double> p;
      if (!sourceToRectified(pin, cam, rect.rot0, Vec2<double>(x, y), p)) continue;
      const float u = sampleBilinear(du, p.x(), p.y());
      if (std::isnan(u)) continue;
      // The rectified point p + (u, 0) in image 1 and p in image 0 share camera 0's centre
      // and ray, so the radial depth triangulated there is camera 0's radial depth.
      out(x, y) = float(triangulateRadial(pin, tpRect, p, Vec2<double>(u, 0.0)));
    }
  return out;
}

}  // namespace cs::baselines

// ---- rectified-tgv ----
#include <chrono>

#include "curvestereo/stereo.hpp"

namespace cs::baselines {

MethodResult runRectifiedTgv(const Rig& rig, const ImageF& left, const ImageF& right, const Params& params,
                             const std::string& backend, double fovDeg, int size) {
  const Rectification rect = makeRectification(rig, fovDeg, size);
  Stereo stereo(rect.rectified, params, backend);
  // The solve is restricted to rectified pixels that see camera 0's image (per rig, untimed).
  ImageU8 mask(size, size, 0);
  for (size_t i = 0; i < mask.size(); ++i) mask.data[i] = std::isfinite(rect.map0.data[i].x) ? 1 : 0;
  stereo.setMask(mask);
  const auto start = std::chrono::steady_clock::now();
  const ImageF l = remap(left, rect.map0), r = remap(right, rect.map1);
  const DepthResult d = stereo.compute(l, r);
  MethodResult res = resultFromDepth(rig, depthToSource(rect, rig.cam0, d.warp));
  res.ms = msSince(start);
  return res;
}

}  // namespace cs::baselines

// The evaluation baselines' geometry: rectification maps and their inverse, the fisheye
// plane sweep on planes of known depth, and rectified TGV on an easy pair.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "baselines/methods.hpp"
#include "baselines/planesweep.hpp"
#include "baselines/rectify.hpp"
#include "curvestereo/metrics.hpp"
#include "curvestereo/triangulate.hpp"
#include "test_util.hpp"

using namespace cs;
using namespace cs::baselines;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A 180-degree equidistant camera of n x n pixels.
Camera fisheye(int n) {
  const double f = n / kPi, c = 0.5 * (n - 1);
  return Camera::kannalaBrandt4(n, n, f, f, c, c);
}

Rig fisheyeRig(int n, const Eigen::Vector3d& centre1, double rotDeg) {
  Rig rig;
  rig.cam0 = rig.cam1 = fisheye(n);
  // Camera 1's axes: camera 0's rotated by rotDeg about (0.2, 1, 0.1).
  const Eigen::Matrix3d Rc0c1 =
      Eigen::AngleAxisd(rotDeg * kPi / 180.0, Eigen::Vector3d(0.2, 1.0, 0.1).normalized()).toRotationMatrix();
  rig.R = Rc0c1.transpose();
  rig.t = -rig.R * centre1;
  return rig;
}

// Smooth, dense procedural texture on a plane (features ~5-30 cm).
double texture(double u, double v) {
  double s = 0.5;
  const double dirs[6][3] = {{0.8, 0.6, 31},  {-0.3, 0.95, 23}, {0.5, -0.87, 41},
                             {0.99, 0.1, 17}, {0.2, 0.98, 53},  {-0.7, -0.7, 37}};
  for (const auto& d : dirs) s += 0.07 * std::sin(d[2] * (d[0] * u + d[1] * v) + d[2]);
  return std::min(1.0, std::max(0.0, s));
}

// Camera k (centre c, X_k = Rk (X0 - c)) sees the plane z0 = Z (camera-0 frame).
// Returns the image (2x2 supersampled) and, for camera 0, the radial depth.
ImageF renderPlane(const Camera& camera, const Eigen::Matrix3d& Rk, const Eigen::Vector3d& c, double Z, ImageF* depth) {
  const BuiltCamera cam(camera);
  ImageF img(camera.width, camera.height, 0.f);
  if (depth) *depth = ImageF(camera.width, camera.height, 0.f);
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      double sum = 0;
      int hits = 0;
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
          Vec3<double> ray;
          if (!cam.unproject(Vec2<double>(x - 0.25 + 0.5 * i, y - 0.25 + 0.5 * j), ray)) continue;
          const Eigen::Vector3d d0 = Rk.transpose() * ray;  // direction in camera-0 frame
          if (d0.z() < 0.05) continue;
          const double s = (Z - c.z()) / d0.z();
          const Eigen::Vector3d X = c + s * d0;
          sum += texture(X.x(), X.y());
          ++hits;
        }
      if (hits) img(x, y) = float(sum / hits);
      Vec3<double> ray;
      if (depth && cam.unproject(Vec2<double>(x, y), ray) && (Rk.transpose() * ray).z() > 0.05)
        (*depth)(x, y) = float(Z / ray.z());
    }
  return img;
}

}  // namespace

TEST_CASE("rectification maps and their inverse round-trip; rows are epipolar lines") {
  const Rig rig = fisheyeRig(240, Eigen::Vector3d(0.2, 0.01, 0.03), 2.0);
  for (double fov : {90.0, 165.0}) {
    const Rectification rect = makeRectification(rig, fov, 160);
    const BuiltCamera pin(rect.rectified.cam0), cam0(rig.cam0);
    int checked = 0;
    for (int y = 0; y < 160; y += 7)
      for (int x = 0; x < 160; x += 7) {
        const Vec2f m = rect.map0(x, y);
        if (!std::isfinite(m.x)) continue;
        Vec2<double> p;
        REQUIRE(sourceToRectified(pin, cam0, rect.rot0, Vec2<double>(m.x, m.y), p));
        CHECK(std::fabs(p.x() - x) < 2e-3);  // float storage of the map
        CHECK(std::fabs(p.y() - y) < 2e-3);
        Vec2<double> back;
        REQUIRE(rectifiedToSource(pin, cam0, rect.rot0, p, back));
        CHECK((back - Vec2<double>(m.x, m.y)).norm() < 1e-6);
        ++checked;
      }
    CHECK(checked > 300);
    // A 3-D point lands on the same row of both rectified images, further left in image 1.
    for (const Eigen::Vector3d& X0 : {Eigen::Vector3d(0.3, -0.2, 2.0), Eigen::Vector3d(-1.0, 0.4, 3.0)}) {
      Vec2<double> p0, p1;
      REQUIRE(pin.project(Vec3<double>(rect.rot0 * X0), p0));
      REQUIRE(pin.project(Vec3<double>(rect.rot1 * (rig.R * X0 + rig.t)), p1));
      CHECK(std::fabs(p0.y() - p1.y()) < 1e-9);
      CHECK(p1.x() < p0.x());
      // Triangulating on the rectified rig gives back the radial depth.
      CHECK(triangulateRadial(pin, rect.rectified.tPrime(), p0, p1 - p0) == doctest::Approx(X0.norm()).epsilon(1e-9));
    }
  }
}

TEST_CASE("rectification handles a baseline along the optical axis") {
  const Rig rig = fisheyeRig(120, Eigen::Vector3d(0.0, 0.0, 0.5), 0.0);
  const Rectification rect = makeRectification(rig, 90, 64);
  CHECK((rect.rot0 * rect.rot0.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-12);
  CHECK(rect.rot0.determinant() == doctest::Approx(1.0));
  CHECK((rect.rot0 * Eigen::Vector3d(0, 0, 0.5)).normalized().isApprox(Eigen::Vector3d::UnitX(), 1e-12));
}

TEST_CASE("plane sweep recovers fronto-parallel planes of known depth") {
  const int n = 200;
  const Rig rig = fisheyeRig(n, Eigen::Vector3d(0.25, 0.0, 0.0), 1.5);
  const BuiltCamera cam0(rig.cam0);
  const Eigen::Vector3d c1 = -rig.R.transpose() * rig.t;
  for (double Z : {1.5, 4.0}) {
    ImageF gt;
    const ImageF left = renderPlane(rig.cam0, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(), Z, &gt);
    const ImageF right = renderPlane(rig.cam1, rig.R, c1, Z, nullptr);
    SweepParams sp;
    sp.scale = 1.0;
    sp.window = 7;
    const SweepResult r = planeSweep(rig, left, right, sp);
    CHECK(r.planes >= 16);
    const ImageF depth = upsampleDepth(r, rig.cam0);
    std::vector<double> rel;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        Vec3<double> ray;
        // Within 50 degrees of the axis: the plane fills that view in both cameras.
        if (!cam0.unproject(Vec2<double>(x, y), ray) || ray.z() < std::cos(50 * kPi / 180)) continue;
        const float d = depth(x, y);
        rel.push_back(std::isfinite(d) ? std::fabs(d - gt(x, y)) / gt(x, y) : 1.0);
      }
    REQUIRE(rel.size() > 5000);
    std::sort(rel.begin(), rel.end());
    INFO("Z = " << Z << " planes " << r.planes);
    // The disparity is ~16 px at 1.5 m and ~4 px at 4 m here: median within 0.1 px of
    // disparity, 90 % within 0.25 px.
    const double disparity = 0.25 * rig.cam0.params[0] / Z;
    CHECK(rel[rel.size() / 2] < 0.1 / disparity);
    CHECK(rel[size_t(0.9 * rel.size())] < 0.25 / disparity);

    // The left-right check keeps (nearly) all of a plane seen by both cameras.
    const SweepResult other = planeSweep(swapRig(rig), right, left, sp);
    const ImageU8 ok = leftRightCheck(rig, r, other, 1.0);
    long long kept = 0, total = 0;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        Vec3<double> ray;
        if (!cam0.unproject(Vec2<double>(x, y), ray) || ray.z() < std::cos(50 * kPi / 180)) continue;
        ++total;
        kept += ok(x, y);
      }
    CHECK(double(kept) / double(total) > 0.9);
  }
}

TEST_CASE("rectified TGV is accurate inside its field of view on an easy pair") {
  const int n = 256;
  const Rig rig = fisheyeRig(n, Eigen::Vector3d(0.15, 0.0, 0.0), 0.0);
  const BuiltCamera cam0(rig.cam0);
  const Eigen::Vector3d c1 = -rig.R.transpose() * rig.t;
  ImageF gt;
  const ImageF left = renderPlane(rig.cam0, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(), 3.0, &gt);
  const ImageF right = renderPlane(rig.cam1, rig.R, c1, 3.0, nullptr);
  Params params = preset("variational");
  // Under the sanitizers 5 warps a level (test_util.hpp): the plane's disparity, about 6 px
  // (f 128 px x 0.15 m / 3 m), is well within their reach (the bounds are the same there).
  params.warps = test::shortUnderSanitizers(20);
  const MethodResult r = runRectifiedTgv(rig, left, right, params, "cpu", 90.0, n);
  ImageF error;
  const Metrics m = evaluate(rig, r.warp, r.depth, gt, nullptr, &error);
  // Inside a 70-degree cone (within the 90-degree rectified view) nearly every pixel is
  // within 1 px; outside the view there is no estimate.
  long long inside = 0, good = 0, outside = 0, outsideEstimated = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      Vec3<double> ray;
      if (std::isnan(error(x, y)) || !cam0.unproject(Vec2<double>(x, y), ray)) continue;
      const double deg = std::acos(ray.z()) * 180 / kPi;
      if (deg < 35) {
        ++inside;
        good += error(x, y) <= 1.0;
      } else if (deg > 65) {
        ++outside;
        outsideEstimated += std::isfinite(error(x, y));
      }
    }
  INFO("tau>1 " << m.tau1 << " density " << m.density);
  REQUIRE(inside > 1000);
  CHECK(double(good) / double(inside) > 0.95);
  CHECK(outsideEstimated == 0);
  CHECK(outside > 0);
  CHECK(m.density < 80);
}

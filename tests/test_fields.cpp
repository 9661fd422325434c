// The per-rig fields against direct projections.
#include <Eigen/Geometry>
#include <cmath>

#include "curvestereo/fields.hpp"
#include "curvestereo/rig.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

Camera t265Like() {
  return Camera::kannalaBrandt4(212, 200, 71.43, 71.69, 105.03, 100.85, -0.0066, 0.0473, -0.0458, 0.0090);
}

Eigen::Matrix3d smallRotation() {
  return Eigen::AngleAxisd(0.02, Eigen::Vector3d(0.3, 1.0, -0.2).normalized()).toRotationMatrix();
}

}  // namespace

TEST_CASE("calibration field is zero for identical unrotated cameras") {
  Camera cam = t265Like();
  RigFields f = computeFields(cam, cam, Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.064, 0, 0), {160.0, 3.0});
  long long valid = 0;
  for (size_t i = 0; i < f.mask.size(); ++i) {
    if (!f.mask.data[i]) continue;
    ++valid;
    CHECK(std::abs(f.calibration.data[i].x) < 1e-4f);
    CHECK(std::abs(f.calibration.data[i].y) < 1e-4f);
  }
  CHECK(valid > 20000);
}

TEST_CASE("calibration field maps each pixel to where its ray lands in camera 1") {
  Camera cam0 = t265Like();
  Camera cam1 = Camera::kannalaBrandt4(212, 200, 71.2, 71.5, 107.0, 99.7, -0.005, 0.039, -0.035, 0.005);
  Eigen::Matrix3d R = smallRotation();
  RigFields f = computeFields(cam0, cam1, R, Eigen::Vector3d(-0.064, 0, 0), {160.0, 3.0});
  const BuiltCamera built0(cam0), built1(cam1);
  for (int y = 5; y < 200; y += 17)
    for (int x = 3; x < 212; x += 13) {
      if (!f.mask(x, y)) continue;
      Vec3<double> ray;
      Vec2<double> px1;
      REQUIRE(built0.unproject(Vec2<double>(x, y), ray));
      REQUIRE(built1.project(Vec3<double>(R * ray), px1));
      CHECK(f.calibration(x, y).x == doctest::Approx(px1.x() - x).epsilon(1e-5));
      CHECK(f.calibration(x, y).y == doctest::Approx(px1.y() - y).epsilon(1e-5));
    }
}

TEST_CASE("trajectory field is the direction in which a point's image moves as its depth decreases") {
  Camera cam = t265Like();
  const Eigen::Vector3d t(-0.064, 0.002, 0.01);
  const Eigen::Matrix3d R = smallRotation();
  RigFields f = computeFields(cam, cam, R, t, {160.0, 3.0});
  const Eigen::Vector3d tPrime = R.transpose() * t;
  const BuiltCamera built(cam);
  int checked = 0;
  for (int y = 4; y < 200; y += 11)
    for (int x = 4; x < 212; x += 11) {
      if (!f.mask(x, y)) continue;
      Vec3<double> ray;
      REQUIRE(built.unproject(Vec2<double>(x, y), ray));
      // A far point (1 km) moved towards the camera: finite-difference image motion.
      Vec2<double> far, nearer;
      REQUIRE(built.project(Vec3<double>(1000.0 * ray + tPrime), far));
      REQUIRE(built.project(Vec3<double>(999.0 * ray + tPrime), nearer));
      Vec2<double> motion = (nearer - far).normalized();
      Vec2<double> field(f.trajectory(x, y).x, f.trajectory(x, y).y);
      CHECK(field.norm() == doctest::Approx(1.0).epsilon(1e-5));
      CHECK(motion.dot(field) > std::cos(1e-3));
      ++checked;
    }
  CHECK(checked > 100);
}

TEST_CASE("forward motion: the epipole region is masked, the rest is valid") {
  Camera cam = Camera::kannalaBrandt4(101, 101, 101 / M_PI, 101 / M_PI, 50, 50);
  RigFields f = computeFields(cam, cam, Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, -0.5), {180.0, 3.0});
  CHECK(f.mask(50, 50) == 0);  // the focus of expansion
  CHECK(f.mask(51, 50) == 0);  // within 3 degrees of it (1 px = 1.8 deg here)
  CHECK(f.mask(50, 30) == 1);
  CHECK(f.mask(0, 0) == 0);  // outside the 180 degree circle
}

TEST_CASE("field of view limit masks rays beyond half the angle") {
  Camera cam = Camera::kannalaBrandt4(101, 101, 101 / M_PI, 101 / M_PI, 50, 50);
  RigFields wide = computeFields(cam, cam, Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.1, 0, 0), {180.0, 3.0});
  RigFields narrow = computeFields(cam, cam, Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.1, 0, 0), {90.0, 3.0});
  CHECK(wide.mask(50, 5) == 1);  // 81 degrees off axis
  CHECK(narrow.mask(50, 5) == 0);
  CHECK(narrow.mask(50, 30) == 1);  // 36 degrees off axis
}

TEST_CASE("the field of view limits camera 1 too: a rotated rig masks the crescent camera 1 does not see") {
  // Equidistant, 1 px = 1.8 degrees, the 180 degree circle (radius 50 px) inside a larger
  // sensor, so that camera 1's projections beyond 90 degrees still land on its image;
  // camera 1 pitched by 9 degrees (5 px) about x.
  Camera cam = Camera::kannalaBrandt4(141, 141, 101 / M_PI, 101 / M_PI, 70, 70);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(9.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  RigFields f = computeFields(cam, cam, R, Eigen::Vector3d(-0.1, 0, 0), {180.0, 3.0});
  const BuiltCamera built(cam);
  auto seenBy1 = [&](int x, int y) {
    Vec3<double> ray;
    REQUIRE(built.unproject(Vec2<double>(x, y), ray));
    const Eigen::Vector3d r1 = R * ray;
    return std::atan2(r1.head<2>().norm(), r1.z()) <= M_PI / 2;
  };
  // Along the vertical through the centre, camera 0's rim (y = 20 and 120 at 90 degrees):
  // the rotation takes one end beyond camera 1's 90 degrees and the other within them.
  int masked = 0;
  for (int y : {20, 21, 22, 118, 119, 120}) {
    CHECK(f.mask(70, y) == (seenBy1(70, y) ? 1 : 0));
    masked += f.mask(70, y) == 0;
  }
  CHECK(masked == 3);          // one end's 3 outermost pixels (85 to 90 degrees > 90 - 9)
  CHECK(f.mask(70, 30) == 1);  // 72 degrees off camera 0's axis, 81 off camera 1's
  CHECK(f.mask(70, 110) == 1);
}

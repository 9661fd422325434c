// Triangulation and the evaluation metrics.
#include <Eigen/Geometry>
#include <cmath>

#include "curvestereo/metrics.hpp"
#include "curvestereo/triangulate.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

Rig testRig() {
  Rig rig;
  rig.cam0 = Camera::kannalaBrandt4(120, 110, 38.0, 38.3, 59.4, 55.1, -0.0066, 0.0473, -0.0458, 0.0090);
  rig.cam1 = rig.cam0;
  rig.R = Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitY()).toRotationMatrix();
  rig.t = Eigen::Vector3d(-0.12, 0.003, 0.01);
  return rig;
}

}  // namespace

TEST_CASE("triangulation inverts warpFromDepth over the image and a range of depths") {
  Rig rig = testRig();
  const BuiltCamera cam0(rig.cam0);
  const Eigen::Vector3d tp = rig.tPrime();
  int checked = 0;
  for (int y = 3; y < 110; y += 9)
    for (int x = 3; x < 120; x += 9)
      for (double depth : {0.5, 2.0, 10.0, 60.0}) {
        Vec2<double> px(x, y), w;
        Vec3<double> ray;
        if (!cam0.unproject(px, ray) || std::atan2(ray.head<2>().norm(), ray.z()) > 1.3) continue;
        if (std::abs(ray.normalized().dot(tp.normalized())) > 0.99) continue;  // near the epipoles
        REQUIRE(warpFromDepth(cam0, tp, px, depth, w));
        CHECK(triangulateRadial(cam0, tp, px, w) == doctest::Approx(depth).epsilon(1e-6));
        ++checked;
      }
  CHECK(checked > 300);
}

TEST_CASE("zero warp means infinite depth; a warp away from the epipolar direction too") {
  Rig rig = testRig();
  const BuiltCamera cam0(rig.cam0);
  CHECK(std::isinf(triangulateRadial(cam0, rig.tPrime(), Vec2<double>(60, 55), Vec2<double>(0, 0))));
  Vec2<double> w;
  REQUIRE(warpFromDepth(cam0, rig.tPrime(), Vec2<double>(60, 55), 3.0, w));
  CHECK(std::isinf(triangulateRadial(cam0, rig.tPrime(), Vec2<double>(60, 55), -w)));
  REQUIRE(warpFromDepth(cam0, rig.tPrime(), Vec2<double>(60, 55), INFINITY, w));
  CHECK(w.norm() < 1e-9);
}

TEST_CASE("triangulate() fills radial, z and points consistently and leaves invalid pixels NaN") {
  Rig rig = testRig();
  const BuiltCamera cam0(rig.cam0);
  FlowImage w(120, 110, Vec2f{0, 0});
  ImageU8 valid(120, 110, 0);
  Vec2<double> wx;
  REQUIRE(warpFromDepth(cam0, rig.tPrime(), Vec2<double>(40, 50), 4.0, wx));
  w(40, 50) = {float(wx.x()), float(wx.y())};
  valid(40, 50) = 1;
  valid(41, 50) = 1;  // zero warp: infinitely far
  DepthMaps d = triangulate(rig.cam0, rig.tPrime(), w, valid);
  CHECK(d.radial(40, 50) == doctest::Approx(4.0).epsilon(1e-4));
  Point3f p = d.points(40, 50);
  CHECK(std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z) == doctest::Approx(4.0).epsilon(1e-4));
  CHECK(d.z(40, 50) == doctest::Approx(p.z).epsilon(1e-5));
  CHECK(std::isinf(d.radial(41, 50)));
  CHECK(std::isnan(d.radial(0, 50)));
}

TEST_CASE("metrics: a perfect estimate has no error; missing and wrong pixels count") {
  Rig rig = testRig();
  ImageF depth(120, 110, 0.f);
  for (int y = 20; y < 90; ++y)
    for (int x = 20; x < 100; ++x) depth(x, y) = 2.f + 0.01f * x;
  depth(30, 30) = INFINITY;  // sky: not evaluated
  FlowImage gt = groundTruthWarp(rig, depth);
  ImageF estDepth = depth;
  Metrics m = evaluate(rig, gt, estDepth, depth, nullptr);
  CHECK(m.evaluated == 80 * 70 - 1);
  CHECK(m.tau1 == 0.0);
  CHECK(m.epe == doctest::Approx(0.0).epsilon(1e-9));
  CHECK(m.density == doctest::Approx(100.0));
  CHECK(m.absRel < 1e-6);

  FlowImage est = gt;
  est(50, 50) = {NAN, NAN};  // missing: an error in tau, not in the mean
  est(51, 50).x += 2.0f;     // wrong by 2 px: > 1, not > 3
  m = evaluate(rig, est, estDepth, depth, nullptr);
  CHECK(m.tau1 == doctest::Approx(100.0 * 2 / m.evaluated));
  CHECK(m.tau3 == doctest::Approx(100.0 * 1 / m.evaluated));
  CHECK(m.density == doctest::Approx(100.0 * (m.evaluated - 1) / m.evaluated));
}

TEST_CASE("metrics: a point hidden from camera 1 is occluded") {
  Rig rig = testRig();
  ImageF depth(120, 110, 5.f), right(120, 110, 5.f);
  // Camera 1 sees something much nearer everywhere: nothing of camera 0's surface at 5 m
  // is visible to it.
  for (float& v : right.data) v = 1.f;
  ImageU8 noc = nonOccludedMask(rig, depth, &right);
  long long n = 0;
  for (auto v : noc.data) n += v;
  CHECK(n == 0);
  noc = nonOccludedMask(rig, depth, nullptr);
  n = 0;
  for (auto v : noc.data) n += v;
  CHECK(n > 1000);
}

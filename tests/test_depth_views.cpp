// Depth for other tools: the virtual pinhole's z-depth is the radial depth re-projected
// (to float precision), the equirectangular range image, camera_info.yaml, the 16-bit
// millimetre PNG and the organised PCD, byte for byte.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "curvestereo/depth_views.hpp"
#include "curvestereo/image_io.hpp"
#include "test_util.hpp"

using cs::DepthSampling;
using cs::ImageF;
using cs::PinholeView;

namespace {

// Ground-truth radial depth of a rendered scene (ground, walls, boxes, poles, sky at
// +inf; 0 outside the image circle): plenty of depth edges.
struct Scene {
  cs::Camera cam0;
  cs::BuiltCamera built0;
  ImageF radial;
};

const Scene& scene() {
  static const Scene s = [] {
    const cs::synth::SynthPair pair = cs::test::smallSynthPair(160, "binocular", 0.12, 7);
    return Scene{pair.rig.cam0, cs::BuiltCamera(pair.rig.cam0), pair.depthLeft};
  }();
  return s;
}

bool equalToFloat(double a, double b) { return std::abs(a - b) <= 2e-7 * std::abs(b); }

std::string readAll(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

}  // namespace

TEST_CASE("pinhole z-depth is the radial depth re-projected, to float precision (nearest)") {
  const Scene& s = scene();
  const PinholeView view = PinholeView::fromFov(100, 120, 90);
  const ImageF z = cs::pinholeDepth(s.cam0, s.radial, view);
  REQUIRE(z.width == 120);
  REQUIRE(z.height == 90);
  int valid = 0, infinite = 0;
  for (int y = 0; y < z.height; ++y)
    for (int x = 0; x < z.width; ++x) {
      CAPTURE(x);
      CAPTURE(y);
      // Independently: the pixel's ray into the fisheye image, the depth at the nearest pixel.
      const cs::Vec3<double> ray((x - view.cx) / view.fx, (y - view.cy) / view.fy, 1.0);
      cs::Vec2<double> p;
      const bool seen = s.built0.project(ray, p) && s.built0.inImage(p);
      const int qx = int(std::floor(p.x() + 0.5)), qy = int(std::floor(p.y() + 0.5));
      const float r = seen && s.radial.inside(qx, qy) ? s.radial(qx, qy) : NAN;
      if (!(r > 0)) {
        CHECK(std::isnan(z(x, y)));
        continue;
      }
      if (std::isinf(r)) {
        CHECK(z(x, y) == INFINITY);
        ++infinite;
        continue;
      }
      // The 3-D point of the z-depth lies at the radial depth: |z * ray / ray_z| = r.
      CHECK(equalToFloat(double(z(x, y)) * ray.norm(), r));
      ++valid;
    }
  CHECK(valid > 4000);
  CHECK(infinite > 100);  // the sky
}

TEST_CASE("bilinear sampling stays on one surface and is exact where it applies") {
  const Scene& s = scene();
  const PinholeView view = PinholeView::fromFov(120, 100, 100);
  const ImageF z = cs::pinholeDepth(s.cam0, s.radial, view, DepthSampling::Bilinear);
  int interpolated = 0;
  for (int y = 0; y < z.height; ++y)
    for (int x = 0; x < z.width; ++x) {
      if (!std::isfinite(z(x, y))) continue;
      const cs::Vec3<double> ray = view.ray(x, y);
      cs::Vec2<double> p;
      REQUIRE(s.built0.project(ray, p));
      const int x0 = int(std::floor(p.x())), y0 = int(std::floor(p.y()));
      const float d[4] = {s.radial(x0, y0), s.radial(x0 + 1, y0), s.radial(x0, y0 + 1), s.radial(x0 + 1, y0 + 1)};
      const double range = double(z(x, y)) * ray.norm();
      const double ax = p.x() - x0, ay = p.y() - y0;
      const double lerp = (1 - ay) * ((1 - ax) * d[0] + ax * d[1]) + ay * ((1 - ax) * d[2] + ax * d[3]);
      const float lo = std::min(std::min(d[0], d[1]), std::min(d[2], d[3]));
      const float hi = std::max(std::max(d[0], d[1]), std::max(d[2], d[3]));
      const bool oneSurface = lo > 0 && std::isfinite(hi) && hi <= lo * (1.f + cs::kBilinearSpread);
      if (oneSurface) {
        CHECK(equalToFloat(range, lerp));
        ++interpolated;
      } else {
        const int qx = int(std::floor(p.x() + 0.5)), qy = int(std::floor(p.y() + 0.5));
        CHECK(equalToFloat(range, s.radial(qx, qy)));  // nearest: no blend across an edge
      }
    }
  CHECK(interpolated > 3000);
}

TEST_CASE("a sphere of radius 3 m: z = 3 cos(angle) in the pinhole, 3 in the equirectangular image") {
  const Scene& s = scene();
  // 3 m inside the 180-degree image circle; 0 ("outside the lens") in the corners, which
  // the lens model maps to rays beyond 90 degrees.
  ImageF sphere(s.radial.width, s.radial.height, 3.f);
  for (size_t i = 0; i < sphere.size(); ++i)
    if (!(s.radial.data[i] > 0)) sphere.data[i] = 0.f;
  const PinholeView view = PinholeView::fromFov(90, 64, 48);
  for (DepthSampling sampling : {DepthSampling::Nearest, DepthSampling::Bilinear}) {
    const ImageF z = cs::pinholeDepth(s.cam0, sphere, view, sampling);
    for (int y = 0; y < z.height; ++y)
      for (int x = 0; x < z.width; ++x) {
        const cs::Vec3<double> ray = view.ray(x, y);
        CHECK(equalToFloat(z(x, y), 3.0 / ray.norm()));
      }
  }
  // The lens sees the front half of the sphere of directions.
  const ImageF range = cs::equirectRange(s.cam0, sphere, 64);
  REQUIRE(range.width == 64);
  REQUIRE(range.height == 32);
  int inside = 0;
  for (int y = 0; y < range.height; ++y)
    for (int x = 0; x < range.width; ++x) {
      const cs::Vec3<double> ray = cs::equirectRay(x, y, 64);
      CHECK(ray.norm() == doctest::Approx(1.0));
      if (ray.z() > 0.05) CHECK(range(x, y) == 3.f);
      if (ray.z() < -0.05) CHECK(std::isnan(range(x, y)));
      inside += range(x, y) == 3.f;
    }
  CHECK(inside > 64 * 32 / 2 - 64);
}

TEST_CASE("equirectangular axes: the centre looks forward, +x right, +y down") {
  const cs::Vec3<double> centre = cs::equirectRay(31.5, 15.5, 64);
  CHECK(centre.z() == doctest::Approx(1.0));
  CHECK(cs::equirectRay(47.5, 15.5, 64).x() == doctest::Approx(1.0));  // longitude +90 deg
  CHECK(cs::equirectRay(31.5, 23.5, 64).y() == doctest::Approx(std::sin(M_PI / 4)));
  CHECK(cs::equirectRay(31.5, 0, 64).y() < -0.99);  // the top row looks up
  CHECK_THROWS_AS(cs::equirectRange(scene().cam0, scene().radial, 63), cs::Error);
}

TEST_CASE("PinholeView::fromFov and its errors") {
  const PinholeView v = PinholeView::fromFov(90, 848, 800);
  CHECK(v.fx == doctest::Approx(424.0));
  CHECK(v.fy == v.fx);
  CHECK(v.cx == 423.5);
  CHECK(v.cy == 399.5);
  CHECK_THROWS_AS(PinholeView::fromFov(180, 10, 10), cs::Error);
  CHECK_THROWS_AS(PinholeView::fromFov(NAN, 10, 10), cs::Error);
  CHECK_THROWS_AS(PinholeView::fromFov(90, 0, 10), cs::Error);
  ImageF wrongSize(10, 10, 1.f);
  CHECK_THROWS_WITH_AS(cs::pinholeDepth(scene().cam0, wrongSize, v), doctest::Contains("camera 0 is 160x160"),
                       cs::Error);
}

TEST_CASE("camera_info.yaml is a ROS CameraInfo of the view") {
  const auto dir = cs::test::tempDir("views_camera_info");
  const PinholeView v = PinholeView::fromFov(100, 640, 480);
  const std::string path = (dir / "camera_info.yaml").string();
  cs::writeCameraInfoYaml(path, v, "cam0_pinhole");
  const YAML::Node info = YAML::LoadFile(path);
  CHECK(info["image_width"].as<int>() == 640);
  CHECK(info["image_height"].as<int>() == 480);
  CHECK(info["camera_name"].as<std::string>() == "cam0_pinhole");
  CHECK(info["distortion_model"].as<std::string>() == "plumb_bob");
  const auto K = info["camera_matrix"]["data"].as<std::vector<double>>();
  CHECK(K == std::vector<double>{v.fx, 0, v.cx, 0, v.fy, v.cy, 0, 0, 1});
  CHECK(info["distortion_coefficients"]["data"].as<std::vector<double>>() == std::vector<double>(5, 0.0));
  CHECK(info["rectification_matrix"]["data"].as<std::vector<double>>() ==
        std::vector<double>{1, 0, 0, 0, 1, 0, 0, 0, 1});
  CHECK(info["projection_matrix"]["data"].as<std::vector<double>>() ==
        std::vector<double>{v.fx, 0, v.cx, 0, 0, v.fy, v.cy, 0, 0, 0, 1, 0});
  CHECK(info["projection_matrix"]["cols"].as<int>() == 4);
}

TEST_CASE("16-bit PNG: millimetres, 0 where invalid or out of range") {
  const auto dir = cs::test::tempDir("views_png");
  ImageF z(6, 1);
  z.data = {1.2345f, 0.0004f, NAN, INFINITY, 70.f, 65.535f};
  const std::string path = (dir / "depth.png").string();
  cs::writeDepthPngMillimetres(path, z);
  cs::PngFormat format;
  const ImageF back = cs::readPngGray(path, &format);
  CHECK(format.bitDepth == 16);
  const long expected[6] = {1235, 0, 0, 0, 0, 65535};
  for (int i = 0; i < 6; ++i) CHECK(std::lround(double(back.data[size_t(i)]) * 65535.0) == expected[i]);
}

TEST_CASE("PCD: the documented header, then W x H x 12 bytes of little-endian float32") {
  const auto dir = cs::test::tempDir("views_pcd");
  cs::Image<cs::Point3f> points(3, 2);
  for (size_t i = 0; i < points.size(); ++i) points.data[i] = {float(i), -0.5f * float(i), 1.f + float(i)};
  points.data[4] = {NAN, NAN, NAN};
  points.data[5] = {1.f, INFINITY, 2.f};  // not a finite point: NaN in the file
  const std::string path = (dir / "points.pcd").string();
  cs::writePcd(path, points);
  const std::string bytes = readAll(path);
  const std::string header =
      "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
      "COUNT 1 1 1\nWIDTH 3\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 6\nDATA binary\n";
  REQUIRE(bytes.size() == header.size() + 6 * 12);
  CHECK(bytes.substr(0, header.size()) == header);
  auto value = [&](size_t point, int field) {
    const unsigned char* b =
        reinterpret_cast<const unsigned char*>(bytes.data() + header.size() + 12 * point + 4 * field);
    const uint32_t bits = uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
    float v;
    std::memcpy(&v, &bits, 4);
    return v;
  };
  for (size_t i = 0; i < 4; ++i) {
    CHECK(value(i, 0) == points.data[i].x);
    CHECK(value(i, 1) == points.data[i].y);
    CHECK(value(i, 2) == points.data[i].z);
  }
  for (size_t i = 4; i < 6; ++i)
    for (int f = 0; f < 3; ++f) CHECK(std::isnan(value(i, f)));
}

// Rigs of N cameras: readers (Kalibr chains, Basalt), pairs, overlap and pair choice, lenses
// wider than 180 degrees, bad rigs' one-line errors, and the per-camera and panorama fusion.
#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <functional>
#include <string>

#include "curvestereo/camera_rig.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/rig_fusion.hpp"
#include "test_util.hpp"

using cs::BodyPose;
using cs::Camera;
using cs::CameraRig;

namespace {

// An equidistant lens of fovDeg whose image circle just fills a size x size image.
Camera equidistant(double fovDeg, int size = 200) {
  const double f = 0.5 * size / (0.5 * fovDeg * M_PI / 180.0);
  return Camera::kannalaBrandt4(size, size, f, f, 0.5 * size - 0.5, 0.5 * size - 0.5);
}

// n cameras yawed by 360/n degrees each on a ring of 8 cm radius (x right, y down, z forward).
CameraRig ring(int n, double fovDeg) {
  CameraRig rig;
  for (int k = 0; k < n; ++k) {
    const double yaw = 2.0 * M_PI * k / n;
    const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
    rig.cameras.push_back(equidistant(fovDeg));
    rig.poses.push_back({R, R * Eigen::Vector3d(0, 0, 0.08)});
  }
  return rig;
}

using cs::test::errorOf;

std::string kalibrText(const CameraRig& rig) {
  const std::string path = (cs::test::tempDir("rig_kalibr") / "camchain.yaml").string();
  cs::saveKalibrRig(rig, path);
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Removes the lines of camK's T_cn_cnm1 (its key and the four rows after it).
std::string withoutPose(std::string text, int k) {
  const size_t cam = text.find("cam" + std::to_string(k) + ":");
  const size_t key = text.find("  T_cn_cnm1:", cam);
  size_t end = key;
  for (int line = 0; line < 5; ++line) end = text.find('\n', end) + 1;
  return text.erase(key, end - key);
}

}  // namespace

TEST_CASE("a Kalibr chain of four cameras reads back the poses it was written with") {
  const CameraRig rig = ring(4, 200);
  const CameraRig back = cs::parseKalibrRig(kalibrText(rig), "ring.yaml");
  REQUIRE(back.size() == 4);
  // The chain starts at camera 0: its pose is the body frame's, the others' are relative to it.
  for (int k = 0; k < 4; ++k) {
    const Eigen::Matrix3d R = rig.poses[0].R.transpose() * rig.poses[size_t(k)].R;
    const Eigen::Vector3d p = rig.poses[0].R.transpose() * (rig.poses[size_t(k)].p - rig.poses[0].p);
    CHECK((back.poses[size_t(k)].R - R).cwiseAbs().maxCoeff() < 1e-12);
    CHECK((back.poses[size_t(k)].p - p).norm() < 1e-12);
  }
  // A pair's pose is the composition of the chain: 0 -> 2 is 1 -> 2 after 0 -> 1.
  const cs::Rig a = cs::pairRig(back, 0, 1), b = cs::pairRig(back, 1, 2), c = cs::pairRig(back, 0, 2);
  CHECK((b.R * a.R - c.R).cwiseAbs().maxCoeff() < 1e-12);
  CHECK((b.R * a.t + b.t - c.t).norm() < 1e-12);
  // The pair readers keep reading a chain's first two cameras.
  const cs::Rig pair = cs::parseKalibr(kalibrText(rig), "ring.yaml");
  CHECK((pair.R - a.R).cwiseAbs().maxCoeff() < 1e-12);
  CHECK((pair.t - a.t).norm() < 1e-12);
}

TEST_CASE("a Basalt file of three cameras gives three cameras posed in the IMU frame") {
  const std::string json = R"({"value0": {
    "T_imu_cam": [{"px": 0.0, "py": 0.0, "pz": 0.08, "qx": 0.0, "qy": 0.0, "qz": 0.0, "qw": 1.0},
                  {"px": 0.06928203230275509, "py": 0.0, "pz": -0.04, "qx": 0.0, "qy": 0.8660254037844386, "qz": 0.0, "qw": 0.5},
                  {"px": -0.06928203230275509, "py": 0.0, "pz": -0.04, "qx": 0.0, "qy": 0.8660254037844387, "qz": 0.0, "qw": -0.5}],
    "intrinsics": [{"camera_type": "kb4", "intrinsics": {"fx": 57.3, "fy": 57.3, "cx": 99.5, "cy": 99.5, "k1": 0, "k2": 0, "k3": 0, "k4": 0}},
                   {"camera_type": "kb4", "intrinsics": {"fx": 57.3, "fy": 57.3, "cx": 99.5, "cy": 99.5, "k1": 0, "k2": 0, "k3": 0, "k4": 0}},
                   {"camera_type": "kb4", "intrinsics": {"fx": 57.3, "fy": 57.3, "cx": 99.5, "cy": 99.5, "k1": 0, "k2": 0, "k3": 0, "k4": 0}}],
    "resolution": [[200, 200], [200, 200], [200, 200]]}})";
  const CameraRig rig = cs::parseCameraRig(json, "calibration.json");
  REQUIRE(rig.size() == 3);
  CHECK((rig.poses[1].p - Eigen::Vector3d(0.06928203230275509, 0, -0.04)).norm() < 1e-15);
  // Camera 1 turned 120 degrees about y: its axis points right and back.
  CHECK((rig.poses[1].R.col(2) - Eigen::Vector3d(std::sin(2 * M_PI / 3), 0, std::cos(2 * M_PI / 3))).norm() < 1e-9);
  CHECK(rig.centre().norm() < 1e-12);
  const std::string three = "[[200, 200], [200, 200], [200, 200]]";
  std::string broken = json;
  broken.replace(broken.find(three), three.size(), "[[200, 200], [200, 200]]");
  const std::string message = errorOf([&] { cs::parseCameraRig(broken, "calibration.json"); });
  CHECK(message.find("have 3, 3 and 2 entries") != std::string::npos);
}

TEST_CASE("bad rigs are refused with one line naming the problem") {
  const CameraRig rig = ring(4, 200);
  const std::string text = kalibrText(rig);
  std::string message = errorOf([&] { cs::parseKalibrRig(withoutPose(text, 2), "rig.yaml"); });
  CHECK(message.find("rig.yaml: missing key \"cam2.T_cn_cnm1\": the chain from cam1 to cam2 is broken") == 0);
  CHECK(message.find('\n') == std::string::npos);

  std::string gap = text;
  gap.replace(gap.find("cam3:"), 5, "cam5:");
  message = errorOf([&] { cs::parseKalibrRig(gap, "rig.yaml"); });
  CHECK(message.find("has cam5 but no cam3") != std::string::npos);

  CameraRig same = rig;
  same.poses[2].p = same.poses[1].p;
  message = errorOf([&] { same.validate(); });
  CHECK(message.find("cam1 and cam2 sit at one centre (zero baseline") == 0);

  // A narrow camera looking up sees nothing the ring's 90-degree views see.
  CameraRig lonely = ring(3, 160);
  lonely.cameras[2] = Camera::pinholeRadtan(200, 200, 275, 275, 99.5, 99.5);
  lonely.poses[2] = {Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix(), {0, -0.2, 0}};
  message = errorOf([&] { lonely.validate(); });
  CHECK(message.find("cam2 overlaps no other camera") == 0);
  message = errorOf([&] { ring(2, 180).validate(); });  // back to back, 180 degrees: no overlap
  CHECK(message.find("cam0 overlaps no other camera") == 0);
}

TEST_CASE("lenses wider than 180 degrees: rays beyond 90 degrees, and back-to-back cameras overlap") {
  const Camera cam = equidistant(220);
  const cs::BuiltCamera built(cam);
  // The image circle reaches the image's edge at 110 degrees off the axis.
  CHECK(cs::viewHalfAngle(cam) == doctest::Approx(110 * M_PI / 180).epsilon(1e-9));
  CHECK(cs::viewHalfAngle(equidistant(160)) == doctest::Approx(M_PI / 2));  // at least the solver's default
  cs::Vec3<double> ray;
  REQUIRE(built.unproject({0.0, 99.5}, ray));  // near the left edge: 109.4 degrees off-axis, behind the camera
  CHECK(ray.z() < -0.3);
  cs::Vec2<double> back;
  REQUIRE(built.project(ray, back));
  CHECK(std::abs(back.x()) < 1e-6);
  // Every fisheye model projects and unprojects a ray 100 degrees off its axis (parameters of
  // lenses wider than 200 degrees).
  for (const Camera& wide : {Camera::kannalaBrandt4(800, 800, 230, 230, 399.5, 399.5, 0.01, -0.002, 0.0003, -0.0001),
                             Camera::doubleSphere(800, 800, 180, 180, 399.5, 399.5, -0.2, 0.6),
                             Camera::extendedUnified(800, 800, 180, 180, 399.5, 399.5, 0.6, 1.1),
                             Camera::unified(800, 800, 400, 400, 399.5, 399.5, 1.5),
                             Camera::mei(800, 800, 400, 400, 399.5, 399.5, 1.5, -0.1, 0.01, 0, 0)}) {
    CAPTURE(wide.modelName());
    const cs::BuiltCamera model(wide);
    const double angle = 100 * M_PI / 180;
    const cs::Vec3<double> p(0.6 * std::sin(angle), 0.8 * std::sin(angle), std::cos(angle));
    cs::Vec2<double> px;
    cs::Vec3<double> r;
    CHECK(model.maxAngle() > angle);
    REQUIRE(model.project(p, px));
    REQUIRE(model.unproject(px, r));
    CHECK((r - p).norm() < 1e-9);
  }
  // Two 220-degree lenses back to back share a 40-degree band all around (at infinity the
  // pixels from 70 to 110 degrees: 60 % of an equidistant circle); 180-degree ones do not.
  const CameraRig wide = ring(2, 220);
  CHECK(cs::pairOverlap(wide, 0, 1) > 0.3);
  CHECK(cs::pairOverlap(wide, 0, 1) < 0.65);
  CHECK(cs::pairOverlap(ring(2, 180), 0, 1) < cs::kMinOverlap);
  CHECK_NOTHROW(wide.validate());
}

TEST_CASE("a pair's solvable window holds every pixel the fields keep, and only the side its partner sees") {
  const cs::FieldOptions fov{180.0, 3.0};
  // Two 180-degree lenses 90 degrees apart on a ring: camera 0 sees camera 1's view with
  // the half of its image on camera 1's side.
  const CameraRig rig = ring(4, 180);
  for (const auto& [i, j] : {std::pair{0, 1}, std::pair{1, 0}, std::pair{0, 3}}) {
    CAPTURE(i);
    CAPTURE(j);
    const cs::Rig pair = cs::pairRig(rig, i, j);
    const cs::ImageWindow w = cs::solvableWindow(pair, fov, 0);
    const cs::RigFields fields = cs::computeFields(pair.cam0, pair.cam1, pair.R, pair.t, fov);
    long long kept = 0, outside = 0;
    for (int y = 0; y < fields.mask.height; ++y)
      for (int x = 0; x < fields.mask.width; ++x) {
        if (!fields.mask(x, y)) continue;
        ++kept;
        outside += x < w.x0 || y < w.y0 || x >= w.x0 + w.width || y >= w.y0 + w.height;
      }
    CHECK(kept > 0);
    CHECK(outside == 0);
    CHECK(w.width < 0.6 * pair.cam0.width);  // about half: the other half faces away from camera j
    CHECK(w.height > 0.9 * pair.cam0.height);
  }
  // The margin grows the window and the image's edges clamp it.
  const cs::Rig pair = cs::pairRig(rig, 0, 1);
  const cs::ImageWindow tight = cs::solvableWindow(pair, fov, 4), grown = cs::solvableWindow(pair, fov, 16);
  CHECK(grown.x0 == std::max(0, tight.x0 - 12));
  CHECK(grown.x0 + grown.width == std::min(pair.cam0.width, tight.x0 + tight.width + 12));
  CHECK(grown.y0 >= 0);
  CHECK(grown.y0 + grown.height <= pair.cam0.height);
  // Two back-to-back 180-degree lenses share no pixel within the field of view.
  const CameraRig backToBack = ring(2, 180);
  CHECK(cs::solvableWindow(cs::pairRig(backToBack, 0, 1), fov, 16).empty());
}

TEST_CASE("pair choice takes the neighbours on a ring, and a given list is checked") {
  const CameraRig rig = ring(4, 200);
  const std::vector<cs::PairInfo> pairs = cs::choosePairs(rig);
  REQUIRE(pairs.size() == 4);
  for (const cs::PairInfo& p : pairs) {
    CHECK((p.j - p.i == 1 || (p.i == 0 && p.j == 3)));  // never the opposite cameras
    CHECK(p.baseline == doctest::Approx(0.08 * std::sqrt(2.0)));
    CHECK(p.overlapIJ > 0.3);
  }
  CHECK(cs::choosePairs(rig, 1).size() >= 2);  // every camera in a pair
  CHECK(cs::parsePairs(rig, "0-1,2-3").size() == 2);
  CHECK(errorOf([&] { cs::parsePairs(rig, "0-4"); }).find("not two cameras of this rig") != std::string::npos);
  CHECK(errorOf([&] { cs::parsePairs(rig, "0-1,1-0"); }).find("given twice") != std::string::npos);
  CHECK(errorOf([&] { cs::parsePairs(ring(4, 180), "0-2"); }).find("overlap too little") != std::string::npos);
}

TEST_CASE("panorama rays follow the rigs' convention and invert") {
  const int width = 64;
  // Column 31.5 is longitude 0 (forward); row 0 looks up (-y); positive longitude is right (+x).
  CHECK((cs::panoramaRay(31.5, 15.5, width) - Eigen::Vector3d(0, 0, 1)).norm() < 1e-12);
  CHECK(cs::panoramaRay(10, 0, width).y() < -0.99);
  CHECK(cs::panoramaRay(47.5, 15.5, width).x() == doctest::Approx(1.0));
  for (const auto& [j, i] : {std::pair{3.0, 7.0}, std::pair{60.25, 20.5}, std::pair{0.0, 31.0}}) {
    const Eigen::Vector2d back = cs::panoramaPixel(cs::panoramaRay(j, i, width), width);
    CHECK(back.x() == doctest::Approx(j));
    CHECK(back.y() == doctest::Approx(i));
  }
  // The frame of a ring pitched down is level: its y axis is the body's.
  CameraRig rig = ring(4, 200);
  for (BodyPose& p : rig.poses) p.R = p.R * Eigen::AngleAxisd(-0.1, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const cs::PanoramaFrame frame = cs::panoramaFrame(rig);
  CHECK((frame.R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-12);
}

namespace {

// A camera's exact result inside a sphere of radius `radius` around the body origin.
cs::DepthResult sphereResult(const CameraRig& rig, int k, double radius, float confidence) {
  const Camera& cam = rig.cameras[size_t(k)];
  const cs::BuiltCamera built(cam);
  const BodyPose& pose = rig.poses[size_t(k)];
  cs::DepthResult r;
  r.valid = cs::ImageU8(cam.width, cam.height, 0);
  r.depth.radial = r.depth.z = r.disparity = cs::ImageF(cam.width, cam.height, NAN);
  r.confidence = cs::ImageF(cam.width, cam.height, NAN);
  r.warp = cs::FlowImage(cam.width, cam.height, {NAN, NAN});
  r.depth.points = cs::Image<cs::Point3f>(cam.width, cam.height, {NAN, NAN, NAN});
  const double cosView = std::cos(cs::viewHalfAngle(cam));
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      cs::Vec3<double> ray;
      if (!built.unproject({double(x), double(y)}, ray) || ray.z() < cosView) continue;
      // |p + s d| = radius for the camera centre p and the ray d in the body frame.
      const Eigen::Vector3d d = pose.R * ray, p = pose.p;
      const double b = p.dot(d), s = -b + std::sqrt(b * b - p.squaredNorm() + radius * radius);
      r.valid(x, y) = 1;
      r.depth.radial(x, y) = float(s);
      r.disparity(x, y) = 1.f;
      r.warp(x, y) = {1.f, 0.f};
      r.confidence(x, y) = confidence;
      r.depth.points(x, y) = {float(s * ray.x()), float(s * ray.y()), float(s * ray.z())};
    }
  return r;
}

// Every pixel of the panorama has a range, and it is the sphere's radius.
void checkWholeSphere(const cs::Panorama& p, float radius) {
  long long filled = 0, wrong = 0;
  for (float v : p.range.data) {
    filled += !std::isnan(v);
    wrong += !std::isnan(v) && std::abs(v - radius) > 1e-3f;
  }
  CHECK(filled == (long long)p.range.size());
  CHECK(wrong == 0);
}

}  // namespace

TEST_CASE("the panorama of exact depths inside a sphere is the sphere's radius, with the nearest surface visible") {
  const CameraRig rig = ring(4, 200);
  std::vector<cs::DepthResult> results;
  for (int k = 0; k < 4; ++k) results.push_back(sphereResult(rig, k, 3.0, 0.8f));
  const cs::PanoramaFrame frame = cs::panoramaFrame(rig);
  const int width = 128;
  cs::Panorama p = cs::fusePanorama(rig, results, {}, frame, width);
  // Four 200-degree lenses see the whole sphere, the poles included: there a camera pixel
  // spans many panorama columns, and its footprint must too.
  checkWholeSphere(p, 3.f);

  // Camera 1 sees a farther surface (a wrong, confident estimate) and a nearer one of low
  // confidence: the nearest confident surface wins where they overlap, then the mean of
  // what agrees with it.
  results[1] = sphereResult(rig, 1, 6.0, 0.8f);
  p = cs::fusePanorama(rig, results, {}, frame, width);
  const Eigen::Vector2d between = cs::panoramaPixel(Eigen::Vector3d(1, 0, 1), width);  // cameras 0 and 1 see it
  CHECK(p.range(int(between.x()), int(between.y())) == doctest::Approx(3.0).epsilon(1e-3));
  results[1] = sphereResult(rig, 1, 1.0, 0.1f);
  p = cs::fusePanorama(rig, results, {}, frame, width);
  CHECK(p.range(int(between.x()), int(between.y())) == doctest::Approx(3.0).epsilon(1e-3));
  CHECK(p.confidence(int(between.x()), int(between.y())) == doctest::Approx(0.8f));
  // Where camera 1 alone has an estimate, it stands, however unconfident, unless the caller
  // leaves out estimates below a confidence.
  for (int k : {0, 2, 3}) results[size_t(k)].valid = cs::ImageU8(200, 200, 0);
  p = cs::fusePanorama(rig, results, {}, frame, width);
  CHECK(p.range(int(between.x()), int(between.y())) == doctest::Approx(1.0).epsilon(1e-3));
  p = cs::fusePanorama(rig, results, {}, frame, width, 0.2f);
  CHECK(std::isnan(p.range(int(between.x()), int(between.y()))));
}

TEST_CASE("a distant surface's estimates within the rig's parallax noise are averaged, not the nearest taken") {
  const CameraRig rig = ring(4, 200);
  // Half a pixel of parallax over the neighbours' 11.3 cm, at the lenses' 57.3 px a radian.
  const double pxPerRadian = 100.0 / (100.0 * M_PI / 180.0);
  const double slack = cs::panoramaParallaxSlack(rig);
  CHECK(slack == doctest::Approx(cs::kPanoramaParallaxPx / (0.08 * std::sqrt(2.0) * pxPerRadian)).epsilon(1e-6));
  std::vector<cs::DepthResult> results;
  for (int k = 0; k < 4; ++k) results.push_back(sphereResult(rig, k, 20.0, 0.8f));
  // 20 and 25 m are 0.01 / m apart in inverse range: a quarter of a pixel here, though a
  // fifth of the range. One surface, so the mean of the inverses, not the nearer.
  results[1] = sphereResult(rig, 1, 25.0, 0.8f);
  const int width = 128;
  const cs::Panorama p = cs::fusePanorama(rig, results, {}, cs::panoramaFrame(rig), width);
  const Eigen::Vector2d between = cs::panoramaPixel(Eigen::Vector3d(1, 0, 1), width);
  CHECK(p.range(int(between.x()), int(between.y())) == doctest::Approx(2.0 / (1.0 / 20 + 1.0 / 25)).epsilon(1e-3));
}

TEST_CASE("a panorama of views (windows of the cameras) fuses as the whole cameras, and bad views are refused") {
  const CameraRig rig = ring(4, 200);
  std::vector<cs::DepthResult> results;
  for (int k = 0; k < 4; ++k) results.push_back(sphereResult(rig, k, 3.0, 0.8f));
  // Each camera as its left and right halves, as a rig's two directions from it solve them.
  std::vector<cs::PanoramaView> views;
  std::vector<cs::DepthResult> halves;
  for (int k = 0; k < 4; ++k)
    for (int x0 : {0, 100}) {
      views.push_back({k, {x0, 0, 100, 200}});
      cs::DepthResult h;
      const cs::DepthResult& r = results[size_t(k)];
      h.valid = cs::ImageU8(100, 200, 0);
      h.depth.radial = h.confidence = cs::ImageF(100, 200, NAN);
      for (int y = 0; y < 200; ++y)
        for (int x = 0; x < 100; ++x) {
          h.valid(x, y) = r.valid(x0 + x, y);
          h.depth.radial(x, y) = r.depth.radial(x0 + x, y);
          h.confidence(x, y) = r.confidence(x0 + x, y);
        }
      halves.push_back(std::move(h));
    }
  const cs::PanoramaFrame frame = cs::panoramaFrame(rig);
  checkWholeSphere(cs::PanoramaFusion(rig, frame, 128, views, {}).fuse(halves, {}), 3.f);
  CHECK(errorOf([&] {
          cs::PanoramaFusion(rig, frame, 128, std::vector<cs::PanoramaView>{{4, {}}}, {});
        }) == "PanoramaFusion: a view of camera 4 in a rig of 4 cameras");
  CHECK(errorOf([&] {
          cs::PanoramaFusion(rig, frame, 128, std::vector<cs::PanoramaView>{{1, {150, 0, 100, 200}}}, {});
        }) == "PanoramaFusion: a view's window does not fit camera 1's image");
  CHECK(errorOf([&] {
          cs::PanoramaFusion(rig, frame, 128, views, {}).fuse(results, {});
        }).find("fusePanorama: 4 results and 0 images for 8 views") == 0);
}

TEST_CASE("a camera's open pixels are completed from a partner's estimate carried into it") {
  const CameraRig rig = ring(4, 200);
  const cs::DepthResult truth0 = sphereResult(rig, 0, 3.0, 0.8f), partner = sphereResult(rig, 1, 3.0, 0.6f);
  cs::DepthResult out = sphereResult(rig, 0, 3.0, 0.8f);
  std::vector<uint8_t> open(200 * 200, 0);
  for (int y = 0; y < 200; ++y)
    for (int x = 100; x < 200; ++x) {  // the right half, which camera 1 (to the right) sees
      open[size_t(y * 200 + x)] = 1;
      out.valid(x, y) = 0;
      out.depth.radial(x, y) = out.confidence(x, y) = NAN;
    }
  const cs::Rig pair = cs::pairRig(rig, 1, 0);
  const long long written = cs::completeFromPartner(pair, {&partner, {}}, cs::cameraRays(rig.cameras[1]),
                                                    cs::cameraRays(rig.cameras[0]), open, out);
  long long right = 0, off = 0, leftChanged = 0;
  for (int y = 0; y < 200; ++y)
    for (int x = 0; x < 200; ++x) {
      if (x < 100) {
        leftChanged += out.depth.radial(x, y) != truth0.depth.radial(x, y) && truth0.valid(x, y);
        continue;
      }
      if (!out.valid(x, y)) continue;
      ++right;
      // The point's own range from camera 0, written to the 2 x 2 pixels about where it
      // lands: within the range's change over a pixel of the sphere.
      off += std::abs(out.depth.radial(x, y) - truth0.depth.radial(x, y)) > 0.01f * truth0.depth.radial(x, y) ||
             out.confidence(x, y) != 0.6f || !std::isnan(out.disparity(x, y));
    }
  CHECK(written == right);
  CHECK(right > 5000);  // most of the right half's image circle
  CHECK(off == 0);
  CHECK(leftChanged == 0);
  // A second partner's farther surface leaves every nearer point of the first where it was:
  // out is the z-buffer across calls.
  const cs::DepthResult farther = sphereResult(rig, 1, 6.0, 0.6f);
  const cs::DepthResult first = out;
  cs::completeFromPartner(pair, {&farther, {}}, cs::cameraRays(rig.cameras[1]), cs::cameraRays(rig.cameras[0]), open,
                          out);
  long long moved = 0;
  for (size_t p = 0; p < out.valid.data.size(); ++p)
    moved += first.valid.data[p] && out.depth.radial.data[p] != first.depth.radial.data[p];
  CHECK(moved == 0);
}

TEST_CASE("a camera's estimates are fused by confidence where they agree") {
  const CameraRig rig = ring(4, 200);
  cs::DepthResult a = sphereResult(rig, 0, 3.0, 0.9f), b = sphereResult(rig, 0, 3.0, 0.3f);
  const int x = 100, y = 100;
  const double d = a.depth.radial(x, y);
  b.depth.radial(x, y) = float(1.03 * d);                     // agrees: the confidence-weighted mean of inverse depths
  b.depth.radial(x + 1, y) = 2.f * a.depth.radial(x + 1, y);  // disagrees: the confident one stands
  b.valid(x + 2, y) = 0, a.valid(x + 3, y) = 0;
  const cs::DepthResult f = cs::fuseCameraEstimates(rig.cameras[0], {&a, &b});
  const double expected = 1.0 / ((0.9 / d + 0.3 / double(b.depth.radial(x, y))) / 1.2);
  CHECK(f.depth.radial(x, y) == doctest::Approx(expected).epsilon(1e-6));
  CHECK(f.depth.radial(x + 1, y) == a.depth.radial(x + 1, y));
  CHECK(f.confidence(x + 3, y) == doctest::Approx(0.3f));  // only b there
  CHECK(f.valid(x + 2, y) == 1);
  // A result without its confidence cannot be fused: one line, not a read out of bounds.
  cs::DepthResult bare = a;
  bare.confidence = cs::ImageF();
  CHECK(errorOf([&] {
          cs::fuseCameraEstimates(rig.cameras[0], {&a, &bare});
        }).find("needs every output") != std::string::npos);
  std::vector<cs::DepthResult> results(4, a);
  results[2] = bare;
  CHECK(errorOf([&] {
          cs::fusePanorama(rig, results, {}, cs::panoramaFrame(rig), 64);
        }).find("fusePanorama: a result for a camera of 200x200 px needs valid, depth and confidence") == 0);
  // The points follow the fused depth along the pixel's ray.
  const cs::Point3f q = f.depth.points(x, y);
  CHECK(std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z) == doctest::Approx(expected).epsilon(1e-5));
}

// The window's pixels of a result, as a solve on that window returns them.
cs::DepthResult windowOf(const cs::DepthResult& r, const cs::ImageWindow& w) {
  cs::DepthResult out;
  out.valid = cs::ImageU8(w.width, w.height), out.confidence = cs::ImageF(w.width, w.height);
  out.depth.radial = cs::ImageF(w.width, w.height), out.disparity = cs::ImageF(w.width, w.height);
  out.warp = cs::FlowImage(w.width, w.height);
  for (int y = 0; y < w.height; ++y)
    for (int x = 0; x < w.width; ++x) {
      out.valid(x, y) = r.valid(x + w.x0, y + w.y0), out.confidence(x, y) = r.confidence(x + w.x0, y + w.y0);
      out.depth.radial(x, y) = r.depth.radial(x + w.x0, y + w.y0);
      out.disparity(x, y) = r.disparity(x + w.x0, y + w.y0), out.warp(x, y) = r.warp(x + w.x0, y + w.y0);
    }
  return out;
}

TEST_CASE("estimates of windows fuse as the same estimates over the whole image with nothing outside") {
  const CameraRig rig = ring(4, 200);
  const cs::Camera& cam = rig.cameras[0];
  const cs::DepthResult a = sphereResult(rig, 0, 3.0, 0.9f);
  cs::DepthResult b = sphereResult(rig, 0, 3.5, 0.95f);  // more confident, and disagrees inside its window
  for (int y = 0; y < cam.height; y += 3) b.depth.radial(y % cam.width, y) *= 0.99f;  // and agrees here and there
  const cs::ImageWindow window{37, 11, 120, 150};
  // The whole-image equivalent: b only inside the window.
  cs::DepthResult bWhole = b;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x)
      if (x < window.x0 || y < window.y0 || x >= window.x0 + window.width || y >= window.y0 + window.height)
        bWhole.valid(x, y) = 0;
  const cs::DepthResult bWindow = windowOf(b, window);
  const cs::CameraRays rays = cs::cameraRays(cam);
  cs::DepthResult whole, placed;
  cs::fuseCameraEstimates(cam, std::vector<const cs::DepthResult*>{&a, &bWhole}, rays, whole);
  cs::fuseCameraEstimates(cam, std::vector<cs::PlacedEstimate>{{&a, {}}, {&bWindow, window}}, rays, placed);
  CHECK(placed.valid.data == whole.valid.data);
  CHECK(cs::test::sameBits(placed.depth.radial, whole.depth.radial));
  CHECK(cs::test::sameBits(placed.confidence, whole.confidence));
  CHECK(cs::test::sameBits(placed.disparity, whole.disparity));
  CHECK(placed.confidence(50, 50) == 0.95f);  // b's, inside its window
  CHECK(placed.confidence(20, 50) == 0.9f);   // a's, left of it
  // A result that is not its window's size is refused in one line.
  CHECK(errorOf([&] {
          cs::fuseCameraEstimates(cam, std::vector<cs::PlacedEstimate>{{&bWindow, {0, 0, 100, 150}}}, rays, placed);
        }).find("fuseCameraEstimates: a result for a camera of 100x150 px") == 0);
}

TEST_CASE("the cross-check between a pair's directions takes away what the other direction contradicts") {
  const CameraRig rig = ring(4, 200);
  cs::DepthResult forward = sphereResult(rig, 0, 3.0, 0.9f);
  const cs::DepthResult backward = sphereResult(rig, 1, 3.0, 0.9f);
  const cs::Rig pair = cs::pairRig(rig, 0, 1);
  CHECK(cs::crossCheck(pair, forward, backward, 0.05) == 0);  // one sphere seen from both
  // (145, 100) looks 45 degrees to the right, where camera 1 sees too; (54, 100) to the left,
  // where it does not: only the first can be contradicted.
  forward.depth.radial(145, 100) = 1.5f;
  forward.depth.radial(54, 100) = 1.5f;
  CHECK(cs::crossCheck(pair, forward, backward, 0.05) == 1);
  CHECK(forward.valid(145, 100) == 0);
  CHECK(std::isnan(forward.depth.radial(145, 100)));
  CHECK(std::isnan(forward.confidence(145, 100)));
  CHECK(forward.valid(54, 100) == 1);
  CHECK(forward.depth.radial(54, 100) == 1.5f);
}

TEST_CASE("rig4_urban_dev: four cameras in a ring, its neighbours paired, the panorama frame its body's") {
  const std::string path = cs::test::sharedData("rigs/rig4_urban_dev/camchain.yaml");
  if (path.empty()) {
    MESSAGE("skipped: ../shared/data/rigs/rig4_urban_dev not present");
    return;
  }
  const CameraRig rig = cs::loadCameraRig(path);
  REQUIRE(rig.size() == 4);
  // The body frame of rig.json: camera 0 at (0, 0, 0.08) pitched 5 degrees down; the
  // panorama's frame, expressed in camera 0's, must be that body frame.
  const Eigen::Matrix3d bodyFromCam0 =
      Eigen::AngleAxisd(-5.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const cs::PanoramaFrame frame = cs::panoramaFrame(rig);
  CHECK((frame.R - bodyFromCam0.transpose()).cwiseAbs().maxCoeff() < 1e-9);
  CHECK((bodyFromCam0 * frame.centre + Eigen::Vector3d(0, 0, 0.08)).norm() < 1e-9);
  const std::vector<cs::PairInfo> pairs = cs::choosePairs(rig);
  REQUIRE(pairs.size() == 4);
  for (const cs::PairInfo& p : pairs) CHECK(std::abs(p.i - p.j) != 2);
}

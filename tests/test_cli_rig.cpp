// The command line of a rig (issue 32): `run` with one image per camera writes cam<k>/ and
// the panorama, `eval` on a rig folder scores them, `calib show` prints the overlaps, and bad
// rigs or options are one line. The end-to-end cases use rig4_urban_dev at a quarter of its
// resolution (skipped without ../shared/data).
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.hpp"
#include "curvestereo/camera_rig.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/rig_fusion.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using cs::test::checkRefused;
using cs::test::CliOutcome;
using cs::test::runCli;

namespace {

// rig4_urban_dev at a quarter of its resolution, in the rig folder layout; "" without the data.
fs::path makeSmallRigFolder() {
  const std::string source = cs::test::sharedData("rigs/rig4_urban_dev");
  if (source.empty()) return {};
  const fs::path dir = cs::test::tempDir("cli_rig_small");
  cs::CameraRig rig = cs::loadCameraRig(source + "/camchain.yaml");
  for (cs::Camera& cam : rig.cameras) cam = cam.scaled(0.25);
  cs::saveKalibrRig(rig, (dir / "camchain.yaml").string());
  for (int k = 0; k < rig.size(); ++k) {
    const std::string n = std::to_string(k);
    cs::writePngGray((dir / ("cam" + n + ".png")).string(),
                     cs::test::shrink(cs::readPngGray(source + "/cam" + n + ".png"), 4, true));
    cs::writeExr((dir / ("depth" + n + ".exr")).string(),
                 cs::test::shrink(cs::readExr(source + "/depth" + n + ".exr"), 4, false));
  }
  cs::writeExr((dir / "panorama_range.exr").string(),
               cs::test::shrink(cs::readExr(source + "/panorama_range.exr"), 4, false));
  return dir;
}

// A copy of that folder for one case (each writes its own outputs there): made once, as
// reading and shrinking the full-resolution files is most of its time.
fs::path smallRigFolder(const std::string& name) {
  static const fs::path made = makeSmallRigFolder();
  if (made.empty()) return {};
  const fs::path dir = cs::test::tempDir(name);
  fs::copy(made, dir, fs::copy_options::recursive);
  return dir;
}

// The median of |a - b| / b where both are finite and positive.
double medianRelativeError(const cs::ImageF& a, const cs::ImageF& b, long long* compared = nullptr) {
  std::vector<double> e;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::isfinite(a.data[i]) && std::isfinite(b.data[i]) && a.data[i] > 0 && b.data[i] > 0)
      e.push_back(std::abs(a.data[i] - b.data[i]) / b.data[i]);
  if (compared) *compared = (long long)e.size();
  if (e.empty()) return INFINITY;
  std::nth_element(e.begin(), e.begin() + long(e.size() / 2), e.end());
  return e[e.size() / 2];
}

std::string images(int n) {
  std::string s;
  for (int k = 0; k < n; ++k) s += " cam" + std::to_string(k) + ".png";
  return s;
}

}  // namespace

TEST_CASE("run with four images: every camera's outputs in cam<k>/ and a panorama near the truth") {
  const fs::path dir = smallRigFolder("cli_rig_run");
  if (dir.empty()) {
    MESSAGE("skipped: ../shared/data/rigs/rig4_urban_dev not present");
    return;
  }
  const CliOutcome o =
      runCli(dir, "run --calib camchain.yaml" + images(4) + " -o out --backend cpu --preset fast --panorama-width 512");
  CAPTURE(o.err);
  REQUIRE(o.exitCode == 0);
  CHECK(o.out.find("pairs: 0-1") != std::string::npos);
  for (int k = 0; k < 4; ++k) {
    const fs::path cam = dir / "out" / ("cam" + std::to_string(k));
    for (const char* file : {"depth.exr", "depth.png", "disparity.exr", "flow.flo", "points.ply", "points.pcd",
                             "confidence.exr", "confidence.png"})
      CHECK(fs::exists(cam / file));
    long long compared = 0;
    const double error =
        medianRelativeError(cs::readExr((cam / "depth.exr").string()),
                            cs::readExr((dir / ("depth" + std::to_string(k) + ".exr")).string()), &compared);
    CAPTURE(k);
    CHECK(compared > 200 * 200 / 3);  // about half of each image overlaps a partner's
    // At a quarter of the resolution a pixel of disparity is four of the original's: a few
    // percent is what the solver gives; a wrong pose or frame gives tens of percent.
    CHECK(error < 0.10);
  }
  for (const char* file : {"panorama_range.exr", "panorama.png", "panorama_confidence.exr", "points.ply"})
    CHECK(fs::exists(dir / "out" / file));
  const cs::ImageF range = cs::readExr((dir / "out" / "panorama_range.exr").string());
  REQUIRE(range.width == 512);
  REQUIRE(range.height == 256);
  long long compared = 0;
  CHECK(medianRelativeError(range, cs::readExr((dir / "panorama_range.exr").string()), &compared) < 0.05);
  CHECK(compared > 512 * 256 / 2);
}

TEST_CASE("run --rig with two images: a rig of two cameras gets per-camera outputs and a panorama") {
  const fs::path dir = smallRigFolder("cli_rig_two");
  if (dir.empty()) {
    MESSAGE("skipped: ../shared/data/rigs/rig4_urban_dev not present");
    return;
  }
  cs::CameraRig rig = cs::loadCameraRig((dir / "camchain.yaml").string());
  rig.cameras.resize(2);
  rig.poses.resize(2);
  cs::saveKalibrRig(rig, (dir / "two.yaml").string());
  const CliOutcome o = runCli(
      dir, "run --rig --calib two.yaml" + images(2) + " -o out --backend cpu --preset fast --panorama-width 256");
  CAPTURE(o.err);
  REQUIRE(o.exitCode == 0);
  CHECK(o.out.find("pairs: 0-1") != std::string::npos);
  for (const char* file : {"cam0/depth.exr", "cam1/depth.exr", "panorama_range.exr", "points.ply"})
    CHECK(fs::exists(dir / "out" / file));
  // Without --rig two images are a pair, as ever: the outputs of camera 0 in OUT itself.
  REQUIRE(runCli(dir, "run --calib two.yaml" + images(2) + " -o pair --backend cpu --preset fast").exitCode == 0);
  CHECK(fs::exists(dir / "pair" / "depth.exr"));
  CHECK(!fs::exists(dir / "pair" / "cam0"));
}

TEST_CASE("eval on a rig folder: each camera's tau, the panorama's abs-rel, tau and coverage") {
  const fs::path dir = smallRigFolder("cli_rig_eval");
  if (dir.empty()) {
    MESSAGE("skipped: ../shared/data/rigs/rig4_urban_dev not present");
    return;
  }
  const CliOutcome o = runCli(dir, "eval . --backend cpu --preset fast --csv eval.csv");
  CAPTURE(o.err);
  REQUIRE(o.exitCode == 0);
  const std::string csv = cs::test::readFile(dir / "eval.csv");
  CAPTURE(csv);
  auto value = [&](const std::string& key) {
    const size_t at = csv.find("\n" + key + ",");
    REQUIRE(at != std::string::npos);
    return std::stod(csv.substr(at + key.size() + 2));
  };
  for (int k = 0; k < 4; ++k) {
    std::istringstream row(csv.substr(csv.find("\ncam" + std::to_string(k) + ",") + 6));
    double tau1 = 0, tau3 = 0;
    char comma = 0;
    row >> tau1 >> comma >> tau3;
    CHECK(tau3 <= tau1);
    CHECK(tau1 < 30.0);  // a quarter of the resolution: a pixel is four of the original's
  }
  CHECK(value("panorama_coverage") > 90.0);
  CHECK(value("panorama_absrel") < 15.0);
  CHECK(value("panorama_absrel") > 0.0);
  // tau in the panorama's pixels: errors over 3 px are errors over 1 px; some are (a quarter
  // of the resolution), most are not.
  MESSAGE("panorama tau>1 " << value("panorama_tau1") << " %, tau>3 " << value("panorama_tau3") << " %");
  CHECK(value("panorama_tau3") <= value("panorama_tau1"));
  CHECK(value("panorama_tau1") > 0.0);
  CHECK(value("panorama_tau1") < 50.0);
}

TEST_CASE("calib show prints a rig's cameras and overlaps; bad rigs and rig options are one line") {
  const fs::path dir = cs::test::tempDir("cli_rig_errors");
  cs::CameraRig ring;
  for (int k = 0; k < 3; ++k) {
    const double yaw = 2.0 * M_PI * k / 3;
    const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
    ring.cameras.push_back(cs::Camera::kannalaBrandt4(64, 64, 18.3, 18.3, 31.5, 31.5));  // 200 degrees
    ring.poses.push_back({R, R * Eigen::Vector3d(0, 0, 0.1)});
  }
  cs::saveKalibrRig(ring, (dir / "rig.yaml").string());
  CliOutcome o = runCli(dir, "calib show rig.yaml");
  CAPTURE(o.err);
  REQUIRE(o.exitCode == 0);
  CHECK(o.out.find("rig of 3 cameras") != std::string::npos);
  CHECK(o.out.find("cam0-cam1:") != std::string::npos);
  CHECK(o.out.find("pairs run solves (--partners 2): 0-1") != std::string::npos);

  for (int k = 0; k < 3; ++k)
    cs::writePngGray((dir / ("cam" + std::to_string(k) + ".png")).string(), cs::ImageF(64, 64, 0.5f));
  checkRefused(runCli(dir, "run --calib rig.yaml cam0.png cam1.png cam2.png cam0.png -o out"),
               "the rig has 3 cameras: run needs 3 images", 2);
  checkRefused(runCli(dir, "run --calib rig.yaml cam0.png cam1.png cam2.png -o out --pairs 0-3"),
               "--pairs: 0-3 is not two cameras of this rig");
  checkRefused(runCli(dir, "run --calib rig.yaml cam0.png cam1.png -o out --pairs 0-1"), "--pairs is for a rig", 2);
  checkRefused(runCli(dir, "run --calib rig.yaml cam0.png cam1.png -o out --cross-check 0.1"),
               "--cross-check is for a rig", 2);
  checkRefused(runCli(dir, "run --calib rig.yaml cam0.png cam1.png cam2.png -o out --cross-check 2"),
               "--cross-check expects a tolerance in [0, 1]", 2);
  checkRefused(runCli(dir, "run --calib rig.yaml cam0.png cam1.png cam2.png -o out --equirect 64"),
               "--equirect is for a pair", 2);
  std::string text = cs::test::readFile(dir / "rig.yaml");
  text.replace(text.find("cam2:"), 5, "cam7:");
  std::ofstream(dir / "gap.yaml") << text;
  checkRefused(runCli(dir, "calib show gap.yaml"), "has cam7 but no cam2");
}

namespace {

// ring4 as the README of ../shared/data/rigs and `synth --help` describe it, written out
// here apart from the renderer: R_body_cam = Ry(yaw) Rx(-5 deg), the centre 8 cm out along
// the camera's horizontal viewing direction.
std::vector<cs::BodyPose> ring4Poses() {
  std::vector<cs::BodyPose> poses;
  for (int k = 0; k < 4; ++k) {
    const double yaw = k * M_PI / 2, pitch = -5.0 * M_PI / 180.0;
    cs::BodyPose pose;
    pose.R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix() *
             Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()).toRotationMatrix();
    pose.p = 0.08 * Eigen::Vector3d(std::sin(yaw), 0.0, std::cos(yaw));
    poses.push_back(pose);
  }
  return poses;
}

// The panorama's (fractional) pixel toward body point x, by the README's inverse formulas.
Eigen::Vector2d panoramaPixelOf(const cs::ImageF& pano, const Eigen::Vector3d& x) {
  const double lon = std::atan2(x.x(), x.z()), lat = std::atan2(-x.y(), std::hypot(x.x(), x.z()));
  return {(lon + M_PI) / (2 * M_PI) * pano.width - 0.5, (M_PI / 2 - lat) / M_PI * pano.height - 0.5};
}

float panoramaValue(const cs::ImageF& pano, int col, int row) {
  return pano((col % pano.width + pano.width) % pano.width, std::clamp(row, 0, pano.height - 1));
}

// The panorama's range toward x: the inverse range interpolated bilinearly between the four
// pixel centres around the direction (exact to second order on a plane, whose inverse range
// is linear in the direction); NaN where the four are not one surface (within 5 %) or sky.
double panoramaRange(const cs::ImageF& pano, const Eigen::Vector3d& x) {
  const Eigen::Vector2d at = panoramaPixelOf(pano, x);
  const int j = int(std::floor(at.x())), i = int(std::floor(at.y()));
  const double fx = at.x() - j, fy = at.y() - i;
  double inverse = 0, lo = INFINITY, hi = 0;
  for (int v = 0; v < 2; ++v)
    for (int u = 0; u < 2; ++u) {
      const double r = panoramaValue(pano, j + u, i + v);
      lo = std::min(lo, r), hi = std::max(hi, r);
      inverse += (u ? fx : 1 - fx) * (v ? fy : 1 - fy) / r;
    }
  return std::isfinite(hi) && hi < 1.05 * lo ? 1.0 / inverse : NAN;
}

bool panoramaSky(const cs::ImageF& pano, const Eigen::Vector3d& x) {
  const Eigen::Vector2d at = panoramaPixelOf(pano, x);
  return std::isinf(panoramaValue(pano, int(std::lround(at.x())), int(std::lround(at.y()))));
}

struct Agreement {
  long long compared = 0, agreeing = 0, sky = 0, skyAgreeing = 0;
};

// Every 3rd pixel of camera k: its ground-truth point (centre + depth x ray) carried into the
// body frame must lie at the panorama's range in its direction from the body origin, within
// 0.5 % (sky: +inf there too), except on depth edges and where the 8 cm between the camera
// and the centre shows another surface (around near silhouettes).
Agreement panoramaAgreement(const cs::Camera& cam, const cs::BodyPose& pose, const cs::ImageF& depth,
                            const cs::ImageF& pano) {
  const cs::BuiltCamera built(cam);
  Agreement a;
  for (int y = 1; y < depth.height; y += 3)
    for (int x = 1; x < depth.width; x += 3) {
      const float d = depth(x, y);
      cs::Vec3<double> ray;
      if (!(d > 0) || !built.unproject(cs::Vec2<double>(x, y), ray)) continue;
      if (std::isinf(d)) {
        ++a.sky;
        a.skyAgreeing += panoramaSky(pano, pose.R * ray);
        continue;
      }
      const Eigen::Vector3d point = pose.p + pose.R * (double(d) * ray);
      ++a.compared;
      a.agreeing += std::abs(panoramaRange(pano, point) - point.norm()) < 0.005 * point.norm();  // NaN: false
    }
  return a;
}

// Each camera's image and depth in a synth rig folder: the depth agrees with the panorama
// where both see the same point (body poses: camera-to-body in the panorama's frame), and
// every camera sees structure, sky, and its own near object.
void checkAgainstPanorama(const fs::path& rigDir, const cs::CameraRig& rig, const std::vector<cs::BodyPose>& poses,
                          int panoramaWidth) {
  const cs::ImageF pano = cs::readExr((rigDir / "panorama_range.exr").string());
  REQUIRE(pano.width == panoramaWidth);
  REQUIRE(pano.height == panoramaWidth / 2);
  for (int k = 0; k < rig.size(); ++k) {
    const cs::Camera& cam = rig.cameras[size_t(k)];
    const cs::ImageF depth = cs::readExr((rigDir / ("depth" + std::to_string(k) + ".exr")).string());
    REQUIRE(depth.width == cam.width);
    CHECK(cs::readPngGray((rigDir / ("cam" + std::to_string(k) + ".png")).string()).width == cam.width);
    const Agreement a = panoramaAgreement(cam, poses[size_t(k)], depth, pano);
    CAPTURE(k);
    CAPTURE(a.agreeing);
    CAPTURE(a.compared);
    // Every camera sees structure (the scene surrounds the rig), near and far.
    CHECK(a.compared > 300);
    // 88 to 93 % agree at 96 pixels (a depth edge spans a larger share of a small image);
    // the panorama's formulas off by half a pixel leave about 42 %.
    CHECK(a.agreeing > 0.8 * double(a.compared));
    CHECK(a.skyAgreeing >= 0.97 * double(a.sky));
    float nearest = INFINITY;
    for (float d : depth.data)
      if (d > 0) nearest = std::min(nearest, d);
    CHECK(nearest < 1.7f);  // its own near object, 1 to 1.6 m away
  }
}

}  // namespace

TEST_CASE("synth --rig ring4: the folder eval reads, each camera's truth agreeing with the panorama's") {
  const fs::path dir = cs::test::tempDir("cli_synth_rig");
  const CliOutcome o = runCli(dir, "synth --rig ring4 -o ring4 --size 96 --samples 1 --panorama-width 512 --quiet");
  CAPTURE(o.err);
  REQUIRE(o.exitCode == 0);
  const fs::path rigDir = dir / "ring4";
  for (const char* file : {"camchain.yaml", "panorama_range.exr", "panorama.png", "rig.json"})
    CHECK(fs::exists(rigDir / file));

  // The camchain reads back as the layout: every camera's pose relative to camera 0.
  const cs::CameraRig rig = cs::loadCameraRig((rigDir / "camchain.yaml").string());
  REQUIRE(rig.size() == 4);
  cs::CameraRig expected;
  expected.cameras = rig.cameras;
  expected.poses = ring4Poses();
  for (int k = 1; k < 4; ++k) {
    const cs::Rig got = cs::pairRig(rig, 0, k), want = cs::pairRig(expected, 0, k);
    CAPTURE(k);
    CHECK((got.R - want.R).norm() < 1e-9);
    CHECK((got.t - want.t).norm() < 1e-9);
  }
  CHECK(rig.cameras[0].params[0] == doctest::Approx(96 / M_PI));  // 180 degrees across the image

  checkAgainstPanorama(rigDir, rig, expected.poses, 512);

  const CliOutcome e = runCli(rigDir, "eval . --backend cpu --preset fast --csv eval.csv");
  CAPTURE(e.err);
  REQUIRE(e.exitCode == 0);
  const std::string csv = cs::test::readFile(rigDir / "eval.csv");
  CAPTURE(csv);
  const size_t at = csv.find("\npanorama_coverage,");
  REQUIRE(at != std::string::npos);
  CHECK(std::stod(csv.substr(at + 19)) > 80.0);  // about 94 %
  const size_t absrel = csv.find("\npanorama_absrel,");
  REQUIRE(absrel != std::string::npos);
  CHECK(std::stod(csv.substr(absrel + 17)) < 25.0);

  checkRefused(runCli(dir, "synth --rig ring5 -o bad"), "unknown rig layout 'ring5' (expected back2, ring4 or ring6)",
               2);
  checkRefused(runCli(dir, "synth --rig back2 -o bad --motion forward"), "--motion cannot be combined with --rig", 2);
  CHECK(!fs::exists(dir / "bad"));
}

TEST_CASE("synth --rig back2 and ring6: the truth lies in the panorama frame run and eval derive from the camchain") {
  const fs::path dir = cs::test::tempDir("cli_synth_rig_layouts");
  for (const std::string layout : {"back2", "ring6"}) {
    CAPTURE(layout);
    const CliOutcome o =
        runCli(dir, "synth --rig " + layout + " -o " + layout + " --size 96 --samples 1 --panorama-width 512 --quiet");
    CAPTURE(o.err);
    REQUIRE(o.exitCode == 0);
    const cs::CameraRig rig = cs::loadCameraRig((dir / layout / "camchain.yaml").string());
    REQUIRE(rig.size() == (layout == "back2" ? 2 : 6));
    // The camchain's rig has camera 0's frame as its body; eval compares in panoramaFrame(rig).
    const cs::PanoramaFrame frame = cs::panoramaFrame(rig);
    std::vector<cs::BodyPose> poses;
    for (const cs::BodyPose& pose : rig.poses)
      poses.push_back({frame.R.transpose() * pose.R, frame.R.transpose() * (pose.p - frame.centre)});
    checkAgainstPanorama(dir / layout, rig, poses, 512);
    if (layout == "back2") {
      // 220 degrees: depth beyond 90 degrees off the axis (the overlap), none past the circle.
      const cs::ImageF depth = cs::readExr((dir / layout / "depth0.exr").string());
      CHECK(depth(2, 48) > 0);
      CHECK(depth(0, 0) == 0);
      CHECK((poses[1].p - poses[0].p).norm() == doctest::Approx(0.12));
      CHECK(poses[1].R.col(2).dot(poses[0].R.col(2)) == doctest::Approx(-1.0));
    }
  }
}

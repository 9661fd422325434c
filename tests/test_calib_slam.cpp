// Issue 29: the calibration files of SLAM systems. OpenVINS camchains, Kalibr imucam files
// without T_cn_cnm1, Kalibr's MEI model, OpenCV plain lists without an image size,
// ORB-SLAM3 settings (both styles, OpenCV's "key:value"), VINS-Fusion configs with
// camodocal camera files; their writers, round trips and one-line refusals.
#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "calib_checks.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/rig.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using cs::CalibFormat;
using cs::Camera;
using cs::CameraModel;
using cs::Rig;

namespace {

fs::path dataDir() { return fs::path(cs::test::goldenDir()).parent_path() / "data"; }

double rigDifference(const Rig& a, const Rig& b) {
  if (a.cam0.model != b.cam0.model || a.cam1.model != b.cam1.model) return INFINITY;
  if (a.cam0.params.size() != b.cam0.params.size() || a.cam1.params.size() != b.cam1.params.size()) return INFINITY;
  if (a.cam0.width != b.cam0.width || a.cam1.height != b.cam1.height) return INFINITY;
  double d = std::max((a.R - b.R).cwiseAbs().maxCoeff(), (a.t - b.t).cwiseAbs().maxCoeff());
  for (const auto& [ca, cb] : {std::pair{&a.cam0, &b.cam0}, std::pair{&a.cam1, &b.cam1}})
    for (size_t i = 0; i < ca->params.size(); ++i) d = std::max(d, std::abs(ca->params[i] - cb->params[i]));
  return d;
}

std::string readText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

Rig exampleRig(const Camera& cam) {
  Rig rig;
  rig.cam0 = rig.cam1 = cam;
  rig.cam1.params[0] *= 1.0013;
  rig.cam1.params[3] -= 1.7;
  rig.R = Eigen::AngleAxisd(0.0123, Eigen::Vector3d(0.3, -1.0, 0.2).normalized()).toRotationMatrix();
  rig.t = Eigen::Vector3d(-0.0641854, -0.000218299, 0.000111253);
  return rig;
}

const char* kOrbV1 = R"(%YAML:1.0
File.version: "1.0"
Camera.type: "PinHole"
Camera1.fx: 458.654
Camera1.fy: 457.296
Camera1.cx: 367.215
Camera1.cy: 248.375
Camera1.k1: -0.28340811
Camera1.k2: 0.07395907
Camera1.p1: 0.00019359
Camera1.p2: 1.76187114e-05
Camera2.fx: 457.587
Camera2.fy: 456.134
Camera2.cx: 379.999
Camera2.cy: 255.238
Camera2.k1: -0.28368365
Camera2.k2: 0.07451284
Camera2.p1: -0.00010473
Camera2.p2: -3.555907e-05
Camera.width: 752
Camera.height: 480
Stereo.T_c1_c2: !!opencv-matrix
  rows: 4
  cols: 4
  dt: f
  data: [1.0, 0.0, 0.0, 0.11, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0, 0, 0, 1.0]
Viewer.PointSize:2
)";

}  // namespace

TEST_CASE("the format comes from the keys: %YAML:1.0 Kalibr, ORB-SLAM3, VINS-Fusion") {
  CHECK(cs::detectCalibFormat("%YAML:1.0\ncam0:\n  camera_model: pinhole\n") == CalibFormat::Kalibr);
  CHECK(cs::detectCalibFormat("%YAML:1.0\n---\nK1: [1]\n") == CalibFormat::OpenCv);
  CHECK(cs::detectCalibFormat(kOrbV1) == CalibFormat::OrbSlam3);
  CHECK(cs::detectCalibFormat("%YAML:1.0\nCamera.fx: 1\n") == CalibFormat::OrbSlam3);
  CHECK(cs::detectCalibFormat("%YAML:1.0\nbody_T_cam0: []\ncam0_calib: \"a.yaml\"\n") == CalibFormat::VinsFusion);
  checkError("%YAML:1.0\n---\n", {"not a Kalibr camchain", "ORB-SLAM3", "VINS-Fusion"});
}

TEST_CASE("OpenCV's key:value without a space is read as OpenCV reads it") {
  const Rig rig = cs::parseCalibration(kOrbV1, "euroc.yaml");
  CHECK(rig.cam0.model == CameraModel::PinholeRadtan);
  CHECK(rig.cam1.params[7] == -3.555907e-05);
  // Stereo.T_c1_c2 poses camera 2 in camera 1 (right 0.11 m along x): X2 = X1 - (0.11, 0, 0).
  CHECK(rig.t.x() == doctest::Approx(-0.11));
  // Only keys at the start of a line change; a value with colons is left alone.
  const std::string text = std::string(kOrbV1) + "System.url:http://a:b\n";
  CHECK_NOTHROW(cs::parseCalibration(text, "euroc.yaml"));
}

TEST_CASE("ORB-SLAM3 refusals are one line naming the format and the missing piece") {
  const std::string v1 = kOrbV1;
  auto without = [&](const std::string& line) {
    const size_t at = v1.find(line);
    REQUIRE(at != std::string::npos);
    return v1.substr(0, at) + v1.substr(v1.find('\n', at) + 1);
  };
  checkError(without("Camera2.fx"), {"ORB-SLAM3 settings", "Camera2.fx", "rectified"});
  checkError(without("Camera1.cy"), {"ORB-SLAM3 settings", "missing key \"Camera1.cy\""});
  checkError(without("Camera.width"), {"ORB-SLAM3 settings", "Camera.width"});
  checkError(v1.substr(0, v1.find("Stereo.T_c1_c2")), {"ORB-SLAM3 settings", "Stereo.T_c1_c2"});
  std::string type = v1;
  type.replace(type.find("PinHole"), 7, "Rectified");
  checkError(type, {"ORB-SLAM3 settings", "Camera.type 'Rectified'", "PinHole or KannalaBrandt8"});
}

TEST_CASE("Kalibr imucam: T_cn_cnm1 wins over T_cam_imu; missing both is one line") {
  const Rig reference = cs::loadCalibration((dataDir() / "t265_camchain.yaml").string());
  std::string text = readText(dataDir() / "t265-camchain-imucam.yaml");
  checkError(text.substr(0, text.find("cam1:")) + "cam1:\n" + text.substr(text.find("  cam_overlaps: [0]")),
             {"Kalibr camchain", "cam1.T_cn_cnm1", "T_cam_imu"});
  // With a T_cn_cnm1 beside T_cam_imu, T_cn_cnm1 is the stereo pose.
  const std::string withPose =
      text.substr(0, text.find("  cam_overlaps: [0]")) +
      "  T_cn_cnm1:\n  - [1, 0, 0, -0.07]\n  - [0, 1, 0, 0]\n  - [0, 0, 1, 0]\n  - [0, 0, 0, 1]\n" +
      text.substr(text.find("  cam_overlaps: [0]"));
  CHECK(cs::parseCalibration(withPose).t.x() == -0.07);
  CHECK(rigDifference(cs::parseCalibration(text), reference) < 1e-9);
}

TEST_CASE("OpenCV plain lists: D and T as cv::Vec, R as a Rodrigues vector, the size from the caller") {
  const std::string text = readText(dataDir() / "t265_opencv_lists.yaml");
  checkError(text, {"OpenCV stereo calibration", "image_width", "--image-size"});
  cs::CalibHints hints;
  hints.width = 848;
  hints.height = 800;
  const Rig rig = cs::parseCalibration(text, "lists.yaml", nullptr, hints);
  CHECK(rig.cam0.width == 848);
  CHECK(rig.cam1.params[7] == 0.00514926757);
  // A rotation of 0.01 rad about y as OpenCV's 3-value form.
  std::string rodrigues = text;
  const size_t r = rodrigues.find("R: !!opencv-matrix"), t = rodrigues.find("T: [");
  rodrigues.replace(r, t - r, "R: [ 0., 0.01, 0. ]\n");
  const Rig turned = cs::parseCalibration(rodrigues, "lists.yaml", nullptr, hints);
  CHECK(turned.R(0, 2) == doctest::Approx(std::sin(0.01)));
  CHECK(turned.R(2, 0) == doctest::Approx(-std::sin(0.01)));
  // The file's own size wins over the hint.
  CHECK(cs::parseCalibration("image_width: 640\nimage_height: 400\n" + text.substr(text.find("K1:")), "l.yaml", nullptr,
                             hints)
            .cam0.width == 640);
}

TEST_CASE("camodocal files: KANNALA_BRANDT k2..k5, MEI, PINHOLE, parameter by parameter") {
  const Camera kb = cs::parseCamodocal(readText(dataDir() / "vins/t265_left.yaml"));
  CHECK(kb.model == CameraModel::KannalaBrandt4);
  CHECK(kb.params ==
        std::vector<double>{285.722, 286.759, 420.135, 403.394, -0.00659769, 0.0473251, -0.0458264, 0.00897725});
  const Camera mei = cs::parseCamodocal(readText(dataDir() / "vins/mei_left.yaml"));
  CHECK(mei.model == CameraModel::Mei);
  CHECK(mei.params ==
        std::vector<double>{519.4431, 521.3283, 420.135, 403.394, 0.81, -0.3215268, 0.0570208, 0.00012, -8.0e-05});
  const Camera pin = cs::parseCamodocal(
      "%YAML:1.0\n---\nmodel_type: PINHOLE\ncamera_name: camera\nimage_width: 752\nimage_height: 480\n"
      "distortion_parameters:\n   k1: -0.28\n   k2: 0.07\n   p1: 0.0002\n   p2: 1.8e-05\n"
      "projection_parameters:\n   fx: 461.6\n   fy: 460.3\n   cx: 363.0\n   cy: 248.1\n");
  CHECK(pin.model == CameraModel::PinholeRadtan);
  CHECK(pin.params == std::vector<double>{461.6, 460.3, 363.0, 248.1, -0.28, 0.07, 0.0002, 1.8e-05});
  CHECK_THROWS_WITH_AS(cs::parseCamodocal("model_type: SCARAMUZZA\nimage_width: 1\nimage_height: 1\n", "s.yaml"),
                       doctest::Contains("SCARAMUZZA' is not supported (KANNALA_BRANDT, MEI or PINHOLE)"), cs::Error);
}

TEST_CASE("VINS-Fusion refusals name the config, the camera file and the problem") {
  const auto dir = cs::test::tempDir("calib_vins_errors");
  const std::string config = readText(dataDir() / "vins/t265_stereo_config.yaml");
  const fs::path path = dir / "config.yaml";
  std::ofstream(path) << config;  // its camera files are missing here
  CHECK_THROWS_WITH_AS(cs::loadCalibration(path.string()),
                       doctest::Contains("VINS-Fusion config: cam0_calib 't265_left.yaml'"), cs::Error);
  std::ofstream(dir / "t265_left.yaml") << "model_type: KANNALA_BRANDT\nimage_width: 848\nimage_height: 800\n";
  std::ofstream(dir / "t265_right.yaml") << readText(dataDir() / "vins/t265_right.yaml");
  CHECK_THROWS_WITH_AS(cs::loadCalibration(path.string()),
                       doctest::Contains("cam0_calib: t265_left.yaml: missing key \"projection_parameters\""),
                       cs::Error);
  std::string mono = config;
  mono.replace(mono.find("num_of_cam: 2"), 13, "num_of_cam: 1");
  checkError(mono, {"VINS-Fusion config", "num_of_cam is 1", "needs 2"});
}

TEST_CASE("Kalibr omni-radtan and camodocal MEI are one MEI rig") {
  CalibFormat format{};
  const Rig kalibr = cs::loadCalibration((dataDir() / "t265_mei-camchain.yaml").string(), &format);
  CHECK(format == CalibFormat::Kalibr);
  CHECK(kalibr.cam0.model == CameraModel::Mei);
  CHECK(kalibr.cam0.params ==
        std::vector<double>{519.4431, 521.3283, 420.135, 403.394, 0.81, -0.3215268, 0.0570208, 0.00012, -8.0e-05});
  const Rig vins = cs::loadCalibration((dataDir() / "vins/mei_stereo_config.yaml").string(), &format);
  CHECK(format == CalibFormat::VinsFusion);
  CHECK(rigDifference(kalibr, vins) < 1e-9);
}

TEST_CASE("round trips through ORB-SLAM3 and VINS-Fusion; refusals of models they cannot hold") {
  const auto dir = cs::test::tempDir("calib_slam_roundtrip");
  const std::vector<Camera> cameras = {
      Camera::kannalaBrandt4(848, 800, 285.722, 286.759, 420.135, 403.394, -0.0066, 0.0473, -0.0458, 0.009),
      Camera::pinholeRadtan(752, 480, 458.654, 457.296, 367.215, 248.375, -0.2834, 0.0740, 0.00019, 1.8e-05),
      Camera::mei(848, 800, 519.44, 521.33, 420.1, 403.4, 0.81, -0.32, 0.057, 0.00012, -8e-05),
      Camera::unified(512, 512, 300.1, 300.2, 254.9, 256.8, 0.37),
      Camera::doubleSphere(512, 512, 158.3, 158.2, 254.9, 256.9, -0.18, 0.59),
  };
  for (const Camera& cam : cameras) {
    CAPTURE(cam.modelName());
    const Rig rig = exampleRig(cam);
    for (const auto& [format, name] :
         {std::pair{CalibFormat::OrbSlam3, "orb.yaml"}, std::pair{CalibFormat::VinsFusion, "vins.yaml"},
          std::pair{CalibFormat::Kalibr, "camchain.yaml"}}) {
      CAPTURE(name);
      const std::string path = (dir / name).string();
      fs::remove(path);
      const bool orbHolds = cam.model == CameraModel::KannalaBrandt4 || cam.model == CameraModel::PinholeRadtan;
      const bool vinsHolds = orbHolds || cam.model == CameraModel::Mei || cam.model == CameraModel::Unified;
      if ((format == CalibFormat::OrbSlam3 && !orbHolds) || (format == CalibFormat::VinsFusion && !vinsHolds)) {
        CHECK_THROWS_WITH_AS(cs::saveCalibration(rig, path, format), doctest::Contains("cannot represent"), cs::Error);
        CHECK(!fs::exists(path));
        continue;
      }
      cs::saveCalibration(rig, path, format);
      CalibFormat read{};
      Rig back = cs::loadCalibration(path, &read);
      CHECK(read == format);
      if (cam.model == CameraModel::Unified && format == CalibFormat::VinsFusion) {
        CHECK(back.cam0.model == CameraModel::Mei);  // MEI without distortion
        back.cam0 = rig.cam0;
        back.cam1 = rig.cam1;
      }
      CHECK(rigDifference(back, rig) < 1e-12);
    }
  }
}

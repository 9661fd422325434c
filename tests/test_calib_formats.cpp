// Basalt calibration.json and OpenCV FileStorage (YAML, XML) readers and writers, and
// loadCalibration's choice of format: files written from each format's documentation,
// malformed ones (one-line errors naming the file), and round trips through every format.
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

using cs::CalibFormat;
using cs::Camera;
using cs::CameraModel;
using cs::Rig;

namespace {

std::string replaceFirst(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

double maxDifference(const Rig& a, const Rig& b) {
  double d = std::max((a.R - b.R).cwiseAbs().maxCoeff(), (a.t - b.t).cwiseAbs().maxCoeff());
  for (const auto& [ca, cb] : {std::pair{&a.cam0, &b.cam0}, std::pair{&a.cam1, &b.cam1}})
    for (size_t i = 0; i < ca->params.size() && i < cb->params.size(); ++i)
      d = std::max(d, std::abs(ca->params[i] - cb->params[i]) / std::max(1.0, std::abs(ca->params[i])));
  return d;
}

void checkSameRig(const Rig& a, const Rig& b, double tolerance) {
  for (const auto& [ca, cb] : {std::pair{&a.cam0, &b.cam0}, std::pair{&a.cam1, &b.cam1}}) {
    CHECK(ca->model == cb->model);
    CHECK(ca->width == cb->width);
    CHECK(ca->height == cb->height);
    CHECK(ca->params.size() == cb->params.size());
  }
  CHECK(maxDifference(a, b) <= tolerance);
}

// A Basalt calibration.json as the calibrator writes it (cereal: value0, 4-space indent),
// two cameras of one type; T_imu_cam poses the cameras in an IMU frame that is neither.
std::string basaltJson(const std::string& type, const std::string& params0, const std::string& params1) {
  return R"({
    "value0": {
        "T_imu_cam": [
            {
                "px": 0.04557484,
                "py": -0.0711618,
                "pz": -0.04468125,
                "qx": -0.00804313,
                "qy": -0.70499535,
                "qz": 0.70915025,
                "qw": 0.00503905
            },
            {
                "px": -0.05545867,
                "py": -0.06985221,
                "pz": -0.04942002,
                "qx": -0.01309419,
                "qy": -0.70924018,
                "qz": 0.70484096,
                "qw": 0.00384646
            }
        ],
        "intrinsics": [
            {
                "camera_type": ")" +
         type + R"(",
                "intrinsics": {)" +
         params0 + R"(}
            },
            {
                "camera_type": ")" +
         type + R"(",
                "intrinsics": {)" +
         params1 + R"(}
            }
        ],
        "resolution": [
            [
                512,
                512
            ],
            [
                512,
                512
            ]
        ],
        "vignette": [],
        "cam_time_offset_ns": 0
    }
})";
}

const char* kDs0 = R"("fx": 158.28, "fy": 158.27, "cx": 254.96, "cy": 256.88, "xi": -0.172, "alpha": 0.593)";
const char* kPin = R"("fx": 458.6, "fy": 457.3, "cx": 319.5, "cy": 239.5)";
const char* kDs1 = R"("fx": 157.91, "fy": 157.89, "cx": 252.56, "cy": 255.02, "xi": -0.171, "alpha": 0.592)";

// The pose the Basalt example above describes, composed independently of the reader.
void expectedBasaltPose(Eigen::Matrix3d& R, Eigen::Vector3d& t) {
  const Eigen::Quaterniond q0(0.00503905, -0.00804313, -0.70499535, 0.70915025);
  const Eigen::Quaterniond q1(0.00384646, -0.01309419, -0.70924018, 0.70484096);
  const Eigen::Isometry3d T0 = Eigen::Translation3d(0.04557484, -0.0711618, -0.04468125) * q0.normalized();
  const Eigen::Isometry3d T1 = Eigen::Translation3d(-0.05545867, -0.06985221, -0.04942002) * q1.normalized();
  const Eigen::Isometry3d T10 = T1.inverse() * T0;  // camera 0 -> IMU -> camera 1
  R = T10.rotation();
  t = T10.translation();
}

}  // namespace

TEST_CASE("Basalt ds: xi then alpha, the poses composed into camera 0 -> camera 1") {
  CalibFormat format{};
  const Rig rig = cs::parseCalibration(basaltJson("ds", kDs0, kDs1), "calibration.json", &format);
  CHECK(format == CalibFormat::Basalt);
  CHECK(rig.cam0.model == CameraModel::DoubleSphere);
  CHECK(rig.cam0.params == std::vector<double>{158.28, 158.27, 254.96, 256.88, -0.172, 0.593});
  CHECK(rig.cam1.params == std::vector<double>{157.91, 157.89, 252.56, 255.02, -0.171, 0.592});
  CHECK(rig.cam0.width == 512);
  CHECK(rig.cam1.height == 512);
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  expectedBasaltPose(R, t);
  CHECK((rig.R - R).cwiseAbs().maxCoeff() < 1e-12);
  CHECK((rig.t - t).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(rig.t.norm() == doctest::Approx(0.101).epsilon(0.01));  // the TUM-VI-like baseline
}

TEST_CASE("Basalt kb4, eucm, pinhole, pinhole-radtan8 map parameter by parameter") {
  const Rig kb4 = cs::parseBasalt(basaltJson("kb4", R"("fx": 190.97, "fy": 190.97, "cx": 254.93, "cy": 256.89,
                 "k1": 0.0034, "k2": 0.0007, "k3": -0.0020, "k4": 0.0002)",
                                             R"("fx": 190.44, "fy": 190.44, "cx": 252.59, "cy": 254.91,
                 "k1": 0.0034, "k2": 0.0017, "k3": -0.0048, "k4": 0.0013)"));
  CHECK(kb4.cam0.model == CameraModel::KannalaBrandt4);
  CHECK(kb4.cam0.params == std::vector<double>{190.97, 190.97, 254.93, 256.89, 0.0034, 0.0007, -0.0020, 0.0002});

  const Rig eucm = cs::parseBasalt(basaltJson("eucm", R"("fx": 191.4, "fy": 191.3, "cx": 254.9, "cy": 256.9,
      "alpha": 0.629, "beta": 1.04)",
                                              R"("fx": 190.9, "fy": 190.8, "cx": 252.5, "cy": 255.0,
      "alpha": 0.627, "beta": 1.05)"));
  CHECK(eucm.cam0.model == CameraModel::ExtendedUnified);
  CHECK(eucm.cam1.params == std::vector<double>{190.9, 190.8, 252.5, 255.0, 0.627, 1.05});

  const char* pin = R"("fx": 458.6, "fy": 457.3, "cx": 255.5, "cy": 255.5)";
  const Rig pinhole = cs::parseBasalt(basaltJson("pinhole", pin, pin));
  CHECK(pinhole.cam0.model == CameraModel::PinholeRadtan);
  CHECK(pinhole.cam0.params == std::vector<double>{458.6, 457.3, 255.5, 255.5, 0, 0, 0, 0});

  const char* r8 = R"("fx": 458.6, "fy": 457.3, "cx": 255.5, "cy": 255.5, "k1": -0.28, "k2": 0.07,
      "p1": 0.0002, "p2": -0.0001, "k3": 0, "k4": 0, "k5": 0, "k6": 0, "rpmax": 1.2)";
  const Rig radtan8 = cs::parseBasalt(basaltJson("pinhole-radtan8", r8, r8));
  CHECK(radtan8.cam1.params == std::vector<double>{458.6, 457.3, 255.5, 255.5, -0.28, 0.07, 0.0002, -0.0001});
}

TEST_CASE("Basalt ucm is the unified model: the same projection for every ray") {
  const double fx = 300, fy = 301, cx = 255.5, cy = 256.5, alpha = 0.6;
  const std::string ucm = R"("fx": 300, "fy": 301, "cx": 255.5, "cy": 256.5, "alpha": 0.6)";
  const Rig rig = cs::parseBasalt(basaltJson("ucm", ucm, ucm));
  CHECK(rig.cam0.model == CameraModel::Unified);
  CHECK(rig.cam0.params[4] == doctest::Approx(alpha / (1 - alpha)));
  const cs::BuiltCamera cam0(rig.cam0);
  for (double theta = 0; theta < 1.6; theta += 0.1)
    for (double phi = 0; phi < 6.28; phi += 0.7) {
      const cs::Vec3<double> p(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      // Basalt's ucm: f * (x, y) / (alpha |p| + (1 - alpha) z) + c.
      const double den = alpha * p.norm() + (1 - alpha) * p.z();
      cs::Vec2<double> px;
      REQUIRE(cam0.project(p, px));
      CHECK(px.x() == doctest::Approx(fx * p.x() / den + cx).epsilon(1e-12));
      CHECK(px.y() == doctest::Approx(fy * p.y() / den + cy).epsilon(1e-12));
    }
  // alpha = 1 has no finite xi: the extended unified model with beta = 1 is the same lens.
  const std::string one = R"("fx": 300, "fy": 301, "cx": 255.5, "cy": 256.5, "alpha": 1.0)";
  const Rig edge = cs::parseBasalt(basaltJson("ucm", one, one));
  CHECK(edge.cam0.model == CameraModel::ExtendedUnified);
  CHECK(edge.cam0.params == std::vector<double>{300, 301, 255.5, 256.5, 1.0, 1.0});
}

TEST_CASE("Basalt layout variants: no value0 wrapper, compact JSON, tabs, YAML") {
  const std::string compact =
      R"({"T_imu_cam":[{"px":0,"py":0,"pz":0,"qx":0,"qy":0,"qz":0,"qw":1},{"px":0.1,"py":0,"pz":0,)"
      R"("qx":0,"qy":0,"qz":0,"qw":1}],"intrinsics":[{"camera_type":"ds","intrinsics":{)" +
      std::string(kDs0) + R"(}},{"camera_type":"ds","intrinsics":{)" + kDs1 +
      R"(}}],"resolution":[[512,512],[512,512]]})";
  const Rig a = cs::parseCalibration(compact);
  CHECK(a.t.x() == doctest::Approx(-0.1));  // camera 1 at +x in the IMU frame: X1 = X0 - (0.1, 0, 0)
  std::string tabs = basaltJson("ds", kDs0, kDs1);
  for (size_t i = 0; (i = tabs.find("    ", i)) != std::string::npos;) tabs.replace(i, 4, "\t");
  CHECK(maxDifference(cs::parseCalibration(tabs), cs::parseBasalt(basaltJson("ds", kDs0, kDs1))) == 0);
  // More than two cameras: the first two are the stereo pair.
  std::string three = compact;
  three.replace(three.find("],\"intrinsics\""), 0, R"(,{"px":0.2,"py":0,"pz":0,"qx":0,"qy":0,"qz":0,"qw":1})");
  three.replace(three.find("],\"resolution\""), 0,
                R"(,{"camera_type":"pinhole","intrinsics":{)" + std::string(kPin) + "}}");
  three.replace(three.find("]]}"), 3, "],[640,480]]}");
  CHECK(maxDifference(cs::parseCalibration(three), a) == 0);
}

TEST_CASE("Basalt errors are one line naming the file and the problem") {
  const std::string good = basaltJson("ds", kDs0, kDs1);
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    const size_t at = s.find(from);
    REQUIRE(at != std::string::npos);
    return s.replace(at, from.size(), to);
  };
  SUBCASE("syntax") { checkError(good.substr(0, 300), {"JSON syntax error", "line"}); }
  SUBCASE("unknown camera type") {
    checkError(replaced("\"ds\"", "\"fov\""), {"value0.intrinsics[0].camera_type", "'fov'", "not supported"});
  }
  SUBCASE("a parameter of another model") {
    checkError(replaced("\"xi\"", "\"beta\""), {"intrinsics[0].intrinsics", "'beta'", "camera_type ds"});
  }
  SUBCASE("missing parameter") {
    checkError(replaced("\"alpha\": 0.593", "\"xi2\": 0.593"), {"'xi2'"});
    checkError(replaced(", \"alpha\": 0.593", ""), {"missing key", "value0.intrinsics[0].intrinsics.alpha"});
  }
  SUBCASE("one camera") {
    const std::string one =
        R"({"value0": {"T_imu_cam": [{"px": 0, "py": 0, "pz": 0, "qx": 0, "qy": 0, "qz": 0, "qw": 1}],
        "intrinsics": [], "resolution": []}})";
    checkError(one, {"value0.T_imu_cam has 1 entry", "two cameras"});
  }
  SUBCASE("not a unit quaternion") { checkError(replaced("\"qw\": 0.00503905", "\"qw\": 0.9"), {"unit quaternion"}); }
  SUBCASE("bad resolution") {
    checkError(replaced("512,\n                512\n            ],", "512.5, 512],"), {"resolution[0][0]", "whole"});
  }
  SUBCASE("not a number") { checkError(replaced("158.28", "\"abc\""), {"intrinsics[0].intrinsics.fx", "'abc'"}); }
  SUBCASE("radtan8 with rational terms") {
    const char* r8 = R"("fx": 458.6, "fy": 457.3, "cx": 255.5, "cy": 255.5, "k1": -0.28, "k2": 0.07,
      "p1": 0.0002, "p2": -0.0001, "k3": 0.01, "k4": 0, "k5": 0, "k6": 0, "rpmax": 1.2)";
    checkError(basaltJson("pinhole-radtan8", r8, r8), {"k3", "k3..k6 = 0"});
  }
  SUBCASE("same centre") {
    std::string s = good;
    for (const char* p : {"-0.05545867", "-0.06985221", "-0.04942002"})
      s.replace(s.find(p), std::string(p).size(), "0");
    for (const char* p : {"0.04557484", "-0.0711618", "-0.04468125"}) s.replace(s.find(p), std::string(p).size(), "0");
    checkError(s, {"zero baseline", "T_imu_cam"});
  }
}

namespace {

// An OpenCV stereo FileStorage YAML as FileStorage writes it.
std::string openCvYaml(const std::string& model, const std::string& d, int dRows = 4, int dCols = 1) {
  std::string s = "%YAML:1.0\n---\nimage_width: 848\nimage_height: 800\n";
  if (!model.empty()) s += "distortion_model: " + model + "\n";
  for (int i = 1; i <= 2; ++i) {
    const std::string n = std::to_string(i);
    s += "K" + n + ": !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ 2.857e+02, 0., 4.2e+02, 0.,\n" +
         "       2.867e+02, 4.03e+02, 0., 0., 1. ]\n";
    s += "D" + n + ": !!opencv-matrix\n   rows: " + std::to_string(dRows) + "\n   cols: " + std::to_string(dCols) +
         "\n   dt: d\n   data: [ " + d + " ]\n";
  }
  s += "R: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ 1., 0., 0., 0., 1., 0., 0., 0., 1. ]\n";
  s += "T: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [ -6.4e-02, 0., 0. ]\n";
  return s;
}

const char* kFisheyeD = "-6.6e-03, 4.7e-02, -4.6e-02, 9.0e-03";

}  // namespace

TEST_CASE("OpenCV YAML: fisheye and radtan, K/M, R and T as stereoCalibrate returns them") {
  CalibFormat format{};
  const Rig fisheye = cs::parseCalibration(openCvYaml("fisheye", kFisheyeD), "stereo.yml", &format);
  CHECK(format == CalibFormat::OpenCv);
  CHECK(fisheye.cam0.model == CameraModel::KannalaBrandt4);
  CHECK(fisheye.cam0.params == std::vector<double>{285.7, 286.7, 420, 403, -6.6e-03, 4.7e-02, -4.6e-02, 9.0e-03});
  CHECK(fisheye.cam0.width == 848);
  CHECK(fisheye.t == Eigen::Vector3d(-0.064, 0, 0));  // X2 = R X1 + T: Kalibr's T_cn_cnm1 as it is
  CHECK(cs::parseCalibration(openCvYaml("equidistant", kFisheyeD)).cam1.model == CameraModel::KannalaBrandt4);

  const Rig radtan = cs::parseCalibration(openCvYaml("", "-0.28, 0.07, 2e-4, -1e-4, 0.", 1, 5));
  CHECK(radtan.cam0.model == CameraModel::PinholeRadtan);
  CHECK(radtan.cam0.params == std::vector<double>{285.7, 286.7, 420, 403, -0.28, 0.07, 2e-4, -1e-4});
  CHECK(cs::parseCalibration(openCvYaml("plumb_bob", "-0.28, 0.07, 2e-4, -1e-4", 1, 4)).cam0.model ==
        CameraModel::PinholeRadtan);

  std::string m = openCvYaml("fisheye", kFisheyeD);
  for (size_t i; (i = m.find("K")) != std::string::npos;) m[i] = 'M';
  CHECK(maxDifference(cs::parseCalibration(m), fisheye) == 0);
  // Without the %YAML:1.0 header the keys still say OpenCV.
  CHECK(cs::detectCalibFormat(openCvYaml("fisheye", kFisheyeD).substr(14)) == CalibFormat::OpenCv);
}

TEST_CASE("OpenCV errors are one line naming the file and the problem") {
  SUBCASE("4-value D without distortion_model is ambiguous") {
    checkError(openCvYaml("", kFisheyeD), {"D1 has 4 values", "distortion_model: fisheye"});
  }
  SUBCASE("fisheye needs 4") {
    checkError(openCvYaml("fisheye", "0.1, 0.2, 0., 0., 0.", 1, 5), {"D1 has 5 values", "fisheye needs 4"});
  }
  SUBCASE("radtan beyond p2") {
    checkError(openCvYaml("radtan", "-0.28, 0.07, 2e-4, -1e-4, 0.01", 1, 5), {"D1[4]", "not zero"});
  }
  SUBCASE("unknown model") { checkError(openCvYaml("omnidir", kFisheyeD), {"distortion_model 'omnidir'"}); }
  SUBCASE("skew") {
    checkError(replaceFirst(openCvYaml("fisheye", kFisheyeD), "2.857e+02, 0.,", "2.857e+02, 1.5,"), {"K1", "skew"});
  }
  SUBCASE("data does not add up") {
    checkError(replaceFirst(openCvYaml("fisheye", kFisheyeD), "rows: 3", "rows: 4"), {"K1 is 4x3", "9 values"});
  }
  SUBCASE("missing R and T") {
    std::string s = openCvYaml("fisheye", kFisheyeD);
    s = s.substr(0, s.find("R: "));
    checkError(s, {"missing key \"R\"", "extrinsics.yml"});
  }
  SUBCASE("missing size") {
    checkError(replaceFirst(openCvYaml("fisheye", kFisheyeD), "image_width: 848\n", ""), {"image_width", "image size"});
  }
  SUBCASE("R is not a rotation") {
    checkError(replaceFirst(openCvYaml("fisheye", kFisheyeD), "data: [ 1., 0., 0.", "data: [ 2., 0., 0."),
               {"R, T rotation is not a rotation"});
  }
  SUBCASE("Rodrigues vector") {
    std::string s = replaceFirst(openCvYaml("fisheye", kFisheyeD), "R: !!opencv-matrix\n   rows: 3\n   cols: 3",
                                 "R: !!opencv-matrix\n   rows: 3\n   cols: 1");
    s = replaceFirst(s, "data: [ 1., 0., 0., 0., 1., 0., 0., 0., 1. ]", "data: [ 0.01, 0., 0. ]");
    // OpenCV's 3-value rotation (issue 29): 0.01 rad about x, as cv::Rodrigues reads it.
    CHECK(cs::parseCalibration(s).R(2, 1) == doctest::Approx(std::sin(0.01)));
    s = replaceFirst(s, "rows: 3\n   cols: 1\n   dt: d\n   data: [ 0.01, 0., 0. ]",
                     "rows: 2\n   cols: 2\n   dt: d\n   data: [ 1, 0, 0, 1 ]");
    checkError(s, {"R must be a 3x3", "Rodrigues"});
  }
}

TEST_CASE("OpenCV XML: the same rig as YAML; malformed XML is one line") {
  const Rig yaml = cs::parseCalibration(openCvYaml("fisheye", kFisheyeD));
  std::string xml =
      "<?xml version=\"1.0\"?>\n<opencv_storage>\n<image_width>848</image_width>\n"
      "<image_height>800</image_height>\n<distortion_model>fisheye</distortion_model>\n";
  for (int i = 1; i <= 2; ++i) {
    const std::string n = std::to_string(i);
    xml += "<K" + n + " type_id=\"opencv-matrix\">\n  <rows>3</rows>\n  <cols>3</cols>\n  <dt>d</dt>\n  <data>\n" +
           "    2.857e+02 0. 4.2e+02 0. 2.867e+02 4.03e+02 0. 0. 1.</data></K" + n + ">\n";
    xml += "<D" + n + " type_id='opencv-matrix'><rows>4</rows><cols>1</cols><dt>d</dt><data>" +
           "-6.6e-03 4.7e-02 -4.6e-02 9.0e-03</data></D" + n + ">\n";
  }
  xml +=
      "<!-- a comment -->\n<R type_id=\"opencv-matrix\"><rows>3</rows><cols>3</cols><dt>d</dt>"
      "<data>1. 0. 0. 0. 1. 0. 0. 0. 1.</data></R>\n<T type_id=\"opencv-matrix\"><rows>3</rows><cols>1</cols>"
      "<dt>d</dt><data>-6.4e-02 0. 0.</data></T>\n</opencv_storage>\n";
  CalibFormat format{};
  const Rig rig = cs::parseCalibration(xml, "stereo.xml", &format);
  CHECK(format == CalibFormat::OpenCv);
  CHECK(maxDifference(rig, yaml) == 0);

  checkError(xml.substr(0, xml.size() / 2), {"XML syntax error", "line"});
  checkError(replaceFirst(xml, "</rows>", "</cols>"), {"XML syntax error at line 7", "</cols> closes <rows>"});
  checkError("<?xml version=\"1.0\"?>\n<root><a>1</a></root>\n", {"not an OpenCV FileStorage", "<root>"});
  checkError(replaceFirst(xml, "fisheye", "fish&eye;"), {"&eye;"});
}

TEST_CASE("the format comes from the content; unrecognised files are one line") {
  CHECK(cs::detectCalibFormat("cam0:\n  camera_model: pinhole\n") == CalibFormat::Kalibr);
  CHECK(cs::detectCalibFormat("{\"value0\": {}}") == CalibFormat::Basalt);
  CHECK(cs::detectCalibFormat("\xEF\xBB\xBF<?xml version=\"1.0\"?><opencv_storage/>") == CalibFormat::OpenCv);
  CHECK(cs::detectCalibFormat("%YAML:1.0\n---\nK1: !!opencv-matrix\n") == CalibFormat::OpenCv);
  checkError("", {"empty"});
  checkError("  \n\t\n", {"empty"});
  checkError("camera: 1\n", {"not a Kalibr camchain, Basalt calibration.json, OpenCV stereo file", "cam0"});
  checkError("[1, 2, 3]\n", {"not a Kalibr camchain"});
  checkError("{\"value0\": [1, 2", {"JSON syntax error"});
  const std::string missing = (cs::test::tempDir("calib_missing") / "none.json").string();
  CHECK_THROWS_WITH_AS(cs::loadCalibration(missing), doctest::Contains((missing + ": cannot open file").c_str()),
                       cs::Error);
}

namespace {

Rig exampleRig(const Camera& cam) {
  Rig rig;
  rig.cam0 = cam;
  rig.cam1 = cam;
  rig.cam1.params[0] *= 1.0013;
  rig.cam1.params[3] -= 1.7;
  rig.R = Eigen::AngleAxisd(0.0123, Eigen::Vector3d(0.3, -1.0, 0.2).normalized()).toRotationMatrix();
  rig.t = Eigen::Vector3d(-0.0641854, -0.000218299, 0.000111253);
  return rig;
}

std::vector<Camera> everyModel() {
  return {
      Camera::kannalaBrandt4(848, 800, 285.722, 286.759, 420.135, 403.394, -0.00659769, 0.0473251, -0.0458264,
                             0.00897725),
      Camera::pinholeRadtan(752, 480, 458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359,
                            1.76187114e-05),
      Camera::pinholeRadtan(640, 480, 400, 400, 319.5, 239.5),
      Camera::unified(512, 512, 465.0 / 3, 464.1, 254.9, 256.8, 1.9),
      Camera::unified(512, 512, 300.1, 300.2, 254.9, 256.8, 0.37),
      Camera::extendedUnified(512, 512, 191.4, 191.3, 254.9, 256.9, 0.629, 1.0 / 3),
      Camera::doubleSphere(512, 512, 158.3, 158.2, 254.9, 256.9, -0.18, 0.59),
  };
}

}  // namespace

TEST_CASE("round trips: Kalibr -> Basalt -> Kalibr and Kalibr -> OpenCV -> Kalibr give the same rig") {
  const auto dir = cs::test::tempDir("calib_roundtrip");
  for (const Camera& cam : everyModel()) {
    CAPTURE(cam.modelName());
    const Rig rig = exampleRig(cam);
    const std::string kalibr = (dir / "camchain.yaml").string();
    const std::string basalt = (dir / "calibration.json").string();
    const std::string kalibr2 = (dir / "camchain2.yaml").string();
    cs::saveKalibr(rig, kalibr);
    CalibFormat format{};
    cs::saveBasalt(cs::loadCalibration(kalibr), basalt);
    cs::saveKalibr(cs::loadCalibration(basalt, &format), kalibr2);
    CHECK(format == CalibFormat::Basalt);
    checkSameRig(cs::loadCalibration(kalibr2), rig, 1e-12);

    const bool opencv = cam.model == CameraModel::KannalaBrandt4 || cam.model == CameraModel::PinholeRadtan;
    for (const char* name : {"stereo.yaml", "stereo.xml"}) {
      const std::string path = (dir / name).string();
      if (!opencv) {
        CHECK_THROWS_WITH_AS(cs::saveOpenCv(rig, path), doctest::Contains("cannot represent"), cs::Error);
        continue;
      }
      cs::saveOpenCv(cs::loadCalibration(kalibr), path);
      const Rig back = cs::loadCalibration(path, &format);
      CHECK(format == CalibFormat::OpenCv);
      checkSameRig(back, rig, 0);  // the numbers are copied: exact
    }
  }
}

TEST_CASE("writers refuse what a format cannot hold, before writing anything") {
  const auto dir = cs::test::tempDir("calib_refuse");
  Rig mixed = exampleRig(everyModel()[0]);
  mixed.cam1 = Camera::pinholeRadtan(848, 800, 400, 400, 423.5, 399.5, 0.01);
  const std::string path = (dir / "mixed.yaml").string();
  CHECK_THROWS_WITH_AS(cs::saveOpenCv(mixed, path), doctest::Contains("one distortion_model for both cameras"),
                       cs::Error);
  CHECK(!std::filesystem::exists(path));
  Rig zero = exampleRig(everyModel()[0]);
  zero.t.setZero();
  CHECK_THROWS_WITH_AS(cs::saveBasalt(zero, (dir / "z.json").string()), doctest::Contains("invalid rig"), cs::Error);
}

TEST_CASE("a written Basalt file has what Basalt's loader reads") {
  const auto dir = cs::test::tempDir("calib_basalt_fields");
  const std::string path = (dir / "calibration.json").string();
  cs::saveBasalt(exampleRig(everyModel()[1]), path);
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* key :
       {"\"value0\"", "\"T_imu_cam\"", "\"intrinsics\"", "\"resolution\"", "\"calib_accel_bias\"",
        "\"calib_gyro_bias\"", "\"imu_update_rate\"", "\"accel_noise_std\"", "\"gyro_noise_std\"", "\"accel_bias_std\"",
        "\"gyro_bias_std\"", "\"cam_time_offset_ns\"", "\"camera_type\": \"pinhole-radtan8\"", "\"rpmax\""}) {
    CAPTURE(key);
    CHECK(text.find(key) != std::string::npos);
  }
}

// Files print rotations coarsely (as float, to six digits): within a thousandth of
// orthonormal they are rotations, read as the nearest exact one; farther, refused.
TEST_CASE("a rotation printed to six digits is read as the nearest rotation, a wrong one is refused") {
  const auto dir = cs::test::tempDir("coarse_rotation");
  auto write = [&](const std::string& rotation) {
    const std::string path = (dir / "settings.yaml").string();
    std::ofstream(path) << "%YAML:1.0\nFile.version: \"1.0\"\nCamera.type: \"KannalaBrandt8\"\n"
                           "Camera1.fx: 285.0\nCamera1.fy: 285.1\nCamera1.cx: 420.5\nCamera1.cy: 400.7\n"
                           "Camera1.k1: -0.005\nCamera1.k2: 0.042\nCamera1.k3: -0.039\nCamera1.k4: 0.0068\n"
                           "Camera2.fx: 285.2\nCamera2.fy: 284.9\nCamera2.cx: 411.9\nCamera2.cy: 403.4\n"
                           "Camera2.k1: -0.004\nCamera2.k2: 0.038\nCamera2.k3: -0.035\nCamera2.k4: 0.0055\n"
                           "Stereo.T_c1_c2: !!opencv-matrix\n  rows: 4\n  cols: 4\n  dt: f\n  data: ["
                        << rotation << "]\nCamera.width: 848\nCamera.height: 800\n";
    return path;
  };
  // A turn of about 0.4 degrees, each entry rounded to six decimals (|R^T R - I| ~ 1e-6).
  const cs::Rig rig =
      cs::loadCalibration(write("0.999983, 0.00445, 0.003859, 0.0637, -0.004437, 0.999984, -0.003476, "
                                "-0.00025, -0.003874, 0.003459, 0.999986, -0.0000888, 0, 0, 0, 1"));
  CHECK((rig.R.transpose() * rig.R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(rig.t.norm() == doctest::Approx(0.0637).epsilon(1e-3));
  // A shear of 1 %: not a rotation written coarsely.
  CHECK_THROWS_WITH_AS(cs::loadCalibration(write("1, 0.01, 0, 0.0637, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1")),
                       doctest::Contains("not a rotation"), cs::Error);
}

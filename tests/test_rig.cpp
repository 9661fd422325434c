// Rig validation and Kalibr camchain.yaml I/O: exact round trips, one-line error
// messages, and the shared T265 / synthetic calibrations.
#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "curvestereo/image.hpp"
#include "curvestereo/rig.hpp"
#include "test_util.hpp"

using cs::Camera;
using cs::Rig;

namespace {

Rig exampleRig(const Camera& cam0) {
  Rig rig;
  rig.cam0 = cam0;
  rig.cam1 = Camera::kannalaBrandt4(848, 800, 284.936797, 286.006777, 428.135996, 398.920999, -0.00496341488,
                                    0.0392387861, -0.0353808728, 0.00514926757);
  rig.R = Eigen::AngleAxisd(0.0123, Eigen::Vector3d(0.3, -1.0, 0.2).normalized()).toRotationMatrix();
  rig.t = Eigen::Vector3d(-0.0641854, -0.000218299, 0.000111253);
  return rig;
}

std::string writeText(const std::string& testName, const std::string& text) {
  const auto path = cs::test::tempDir(testName) / "camchain.yaml";
  std::ofstream(path) << text;
  return path.string();
}

std::string loadError(const std::string& path) {
  try {
    cs::loadKalibr(path);
  } catch (const cs::Error& e) {
    return e.what();
  }
  return "<no error>";
}

// A valid camchain with hooks to break one part of it.
struct CamchainText {
  std::string cam0Model = "pinhole";
  std::string cam0Distortion = "equidistant";
  std::string cam0Intrinsics = "[285.722, 286.759, 420.135, 403.394]";
  std::vector<std::string> T = {"[1.0, 0.0, 0.0, -0.064]", "[0.0, 1.0, 0.0, 0.0]", "[0.0, 0.0, 1.0, 0.0]",
                                "[0.0, 0.0, 0.0, 1.0]"};
  bool withT = true;

  std::string str() const {
    std::string s = "cam0:\n  camera_model: " + cam0Model + "\n  distortion_coeffs: [0.01, 0.02, 0.0, 0.0]\n" +
                    "  distortion_model: " + cam0Distortion + "\n  intrinsics: " + cam0Intrinsics +
                    "\n  resolution: [848, 800]\ncam1:\n";
    if (withT) {
      s += "  T_cn_cnm1:\n";
      for (const auto& row : T) s += "  - " + row + "\n";
    }
    s += "  camera_model: pinhole\n  distortion_coeffs: [0.0, 0.0, 0.0, 0.0]\n  distortion_model: equidistant\n"
         "  intrinsics: [285.0, 286.0, 428.1, 398.9]\n  resolution: [848, 800]\n";
    return s;
  }
};

// The error must be one line naming the file and containing every key word.
void checkError(const std::string& path, const std::vector<std::string>& keyWords) {
  const std::string msg = loadError(path);
  CAPTURE(msg);
  CHECK(msg.find(path) != std::string::npos);
  CHECK(msg.find('\n') == std::string::npos);
  for (const auto& word : keyWords) {
    CAPTURE(word);
    CHECK(msg.find(word) != std::string::npos);
  }
}

}  // namespace

TEST_CASE("saveKalibr -> loadKalibr is exact for every model") {
  const std::vector<Camera> cams = {
      Camera::kannalaBrandt4(848, 800, 285.722, 286.759, 420.135, 403.394, -0.00659769, 0.0473251, -0.0458264,
                             0.00897725),
      Camera::pinholeRadtan(752, 480, 458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359,
                            1.76187114e-05),
      Camera::unified(512, 512, 465.0 / 3, 464.1, 254.9, 256.8, 1.9),
      Camera::extendedUnified(512, 512, 191.4, 191.3, 254.9, 256.9, 0.629, 1.0 / 3),
      Camera::doubleSphere(512, 512, 158.3, 158.2, 254.9, 256.9, -0.18, 0.59),
      Camera::mei(848, 800, 519.4431, 521.3283, 420.135, 403.394, 0.81, -0.3215268, 0.0570208, 0.00012, -8.0e-05),
  };
  const auto dir = cs::test::tempDir("rig_roundtrip");
  for (const auto& cam : cams) {
    CAPTURE(cam.modelName());
    const Rig rig = exampleRig(cam);
    const std::string path = (dir / (cam.modelName() + ".yaml")).string();
    cs::saveKalibr(rig, path);
    const Rig back = cs::loadKalibr(path);
    for (const auto& [a, b] : {std::pair{&rig.cam0, &back.cam0}, std::pair{&rig.cam1, &back.cam1}}) {
      CHECK(a->model == b->model);
      CHECK(a->width == b->width);
      CHECK(a->height == b->height);
      CHECK(a->params == b->params);  // bit-exact
    }
    CHECK(rig.R == back.R);
    CHECK(rig.t == back.t);
  }
}

TEST_CASE("pinhole + none is radtan with zero distortion") {
  CamchainText text;
  text.cam0Distortion = "none";
  const std::string path = writeText("rig_pinhole_none", text.str());
  // distortion_coeffs are non-zero in the template: refused for "none".
  checkError(path, {"cam0.distortion_coeffs", "none"});

  const std::string ok =
      writeText("rig_pinhole_none_ok",
                "cam0:\n  camera_model: pinhole\n  distortion_model: none\n"
                "  distortion_coeffs: []\n  intrinsics: [400, 400, 320, 240]\n  resolution: [640, 480]\n"
                "cam1:\n  T_cn_cnm1:\n  - [1, 0, 0, -0.1]\n  - [0, 1, 0, 0]\n  - [0, 0, 1, 0]\n"
                "  - [0, 0, 0, 1]\n  camera_model: omni\n  distortion_model: none\n"
                "  intrinsics: [0.9, 400, 400, 320, 240]\n  resolution: [640, 480]\n");
  const Rig rig = cs::loadKalibr(ok);
  CHECK(rig.cam0.model == cs::CameraModel::PinholeRadtan);
  CHECK(rig.cam0.params == std::vector<double>{400, 400, 320, 240, 0, 0, 0, 0});
  CHECK(rig.cam1.model == cs::CameraModel::Unified);
  CHECK(rig.cam1.params == std::vector<double>{400, 400, 320, 240, 0.9});  // Kalibr puts xi first
}

TEST_CASE("loadKalibr errors are one line naming the file and the problem") {
  SUBCASE("missing file") {
    const std::string path = (cs::test::tempDir("rig_missing") / "nope.yaml").string();
    checkError(path, {"does not exist"});
  }
  SUBCASE("malformed YAML") {
    checkError(writeText("rig_syntax", "cam0:\n  intrinsics: [1, 2\n  resolution: {\n"), {"YAML syntax error", "line"});
  }
  SUBCASE("not a mapping") { checkError(writeText("rig_scalar", "just text\n"), {"cam0", "cam1"}); }
  SUBCASE("missing keys") {
    checkError(writeText("rig_nointr", "cam0:\n  camera_model: pinhole\n"), {"missing key", "\"cam0.intrinsics\""});
    CamchainText text;
    const std::string cam0Only = text.str().substr(0, text.str().find("cam1:"));
    checkError(writeText("rig_nocam1", cam0Only), {"missing key", "\"cam1\""});
  }
  SUBCASE("unknown camera model") {
    CamchainText text;
    text.cam0Model = "fisheye42";
    checkError(writeText("rig_unknown", text.str()), {"cam0", "unknown camera_model", "fisheye42"});
  }
  SUBCASE("unsupported model combination") {
    CamchainText text;
    text.cam0Model = "omni";
    text.cam0Distortion = "equidistant";
    text.cam0Intrinsics = "[0.9, 285.722, 286.759, 420.135, 403.394]";
    checkError(writeText("rig_combo", text.str()), {"cam0", "omni+equidistant", "unsupported"});
  }
  SUBCASE("missing T_cn_cnm1") {
    CamchainText text;
    text.withT = false;
    checkError(writeText("rig_noT", text.str()), {"missing key", "\"cam1.T_cn_cnm1\""});
  }
  SUBCASE("non-rotation") {
    CamchainText text;
    text.T[0] = "[1.1, 0.0, 0.0, -0.064]";
    checkError(writeText("rig_notrot", text.str()), {"T_cn_cnm1", "not a rotation", "det="});
  }
  SUBCASE("zero baseline") {
    CamchainText text;
    text.T[0] = "[1.0, 0.0, 0.0, 0.0]";
    checkError(writeText("rig_zerot", text.str()), {"zero baseline"});
  }
  SUBCASE("wrong intrinsics count") {
    CamchainText text;
    text.cam0Intrinsics = "[285.722, 286.759, 420.135]";
    checkError(writeText("rig_intr", text.str()), {"cam0.intrinsics", "has 3 values", "needs 4"});
  }
  SUBCASE("non-numeric value") {
    CamchainText text;
    text.cam0Intrinsics = "[285.722, abc, 420.135, 403.394]";
    checkError(writeText("rig_nan", text.str()), {"cam0.intrinsics[1]", "not a number", "abc", "line 5"});
  }
  SUBCASE("bad last row of T") {
    CamchainText text;
    text.T[3] = "[0.0, 0.0, 1.0, 1.0]";
    checkError(writeText("rig_lastrow", text.str()), {"cam1.T_cn_cnm1", "last row"});
  }
  SUBCASE("T is not 4x4") {
    CamchainText text;
    text.T[2] = "[0.0, 0.0, 1.0]";
    checkError(writeText("rig_T3", text.str()), {"cam1.T_cn_cnm1", "4x4"});
  }
  SUBCASE("invalid camera parameters") {
    CamchainText text;
    text.cam0Intrinsics = "[-285.722, 286.759, 420.135, 403.394]";
    checkError(writeText("rig_badf", text.str()), {"cam0", "focal length"});
  }
}

TEST_CASE("Rig::validate") {
  Rig rig = exampleRig(Camera::kannalaBrandt4(848, 800, 285.7, 286.8, 420.1, 403.4));
  CHECK_NOTHROW(rig.validate());
  CHECK(rig.tPrime().isApprox(rig.R.transpose() * rig.t));

  Rig mirrored = rig;
  mirrored.R = -rig.R;  // orthonormal but det = -1
  CHECK_THROWS_AS(mirrored.validate(), cs::Error);
  Rig zero = rig;
  zero.t.setConstant(1e-8);
  CHECK_THROWS_AS(zero.validate(), cs::Error);
  // Nothing loadKalibr would refuse gets written.
  CHECK_THROWS_AS(cs::saveKalibr(zero, (cs::test::tempDir("rig_save_zero") / "x.yaml").string()), cs::Error);
}

TEST_CASE("the T265 robot calibration loads") {
  const std::string path = cs::test::sharedData("t265/robot/camchain.yaml");
  if (path.empty()) {
    MESSAGE("skipped: ../shared/data/t265 not present");
    return;
  }
  const Rig rig = cs::loadKalibr(path);
  CHECK(rig.cam0.model == cs::CameraModel::KannalaBrandt4);
  CHECK(rig.cam1.model == cs::CameraModel::KannalaBrandt4);
  CHECK(rig.cam0.width == 848);
  CHECK(rig.cam0.height == 800);
  CHECK(rig.cam1.width == 848);
  CHECK(rig.cam0.params[0] == doctest::Approx(285.722));
  CHECK(rig.cam0.params[4] == doctest::Approx(-0.00659769));
  CHECK(rig.t.x() == doctest::Approx(-0.0641854));
  CHECK(rig.R(0, 1) == doctest::Approx(0.000610349928068));
  // The T265 lens covers about 163 deg; its polynomial is monotone to well beyond that.
  CHECK(cs::BuiltCamera(rig.cam0).maxAngle() > 85.0 * M_PI / 180.0);
}

TEST_CASE("every synthetic scene calibration loads") {
  const std::string dir = cs::test::sharedData("synthetic");
  if (dir.empty()) {
    MESSAGE("skipped: ../shared/data/synthetic not present");
    return;
  }
  int loaded = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const auto path = entry.path() / "camchain.yaml";
    if (!std::filesystem::exists(path)) continue;
    CAPTURE(path.string());
    const Rig rig = cs::loadKalibr(path.string());
    CHECK(rig.cam0.model == cs::CameraModel::KannalaBrandt4);
    CHECK(rig.cam0.width == 800);
    CHECK(rig.cam0.params[0] == doctest::Approx(800.0 / M_PI).epsilon(1e-15));
    CHECK(rig.cam0.params[2] == 399.5);
    CHECK(rig.t.norm() > 0.05);
    ++loaded;
  }
  CHECK(loaded > 0);
}

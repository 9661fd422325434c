// Issues 18 and 29: the T265 calibration written by hand in every format read (tests/data/:
// Basalt, OpenCV, OpenVINS, Kalibr imucam, ORB-SLAM3 old and new, VINS-Fusion) is the same
// rig as the Kalibr one, and `curvestereo run` gives the same depth with each on the T265
// pair (when ../shared/data/t265 is present).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "cli_util.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/rig.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

fs::path dataDir() { return fs::path(cs::test::goldenDir()).parent_path() / "data"; }

// The Kalibr reference and the hand-written restatements, with the format each must be read as.
const std::vector<std::pair<std::string, cs::CalibFormat>>& fixtures() {
  static const std::vector<std::pair<std::string, cs::CalibFormat>> f = {
      {"t265_camchain.yaml", cs::CalibFormat::Kalibr},
      {"t265_basalt.json", cs::CalibFormat::Basalt},
      {"t265_opencv.yaml", cs::CalibFormat::OpenCv},
      {"t265_opencv.xml", cs::CalibFormat::OpenCv},
  };
  return f;
}

// Restatements through the IMU frame or a transform's inverse, or without the image size:
// the same rig to rounding.
const std::vector<std::pair<std::string, cs::CalibFormat>>& composedFixtures() {
  static const std::vector<std::pair<std::string, cs::CalibFormat>> f = {
      {"t265_opencv_lists.yaml", cs::CalibFormat::OpenCv},  // no image size: the caller's
      {"t265_openvins.yaml", cs::CalibFormat::Kalibr},
      {"t265-camchain-imucam.yaml", cs::CalibFormat::Kalibr},
      {"t265_orbslam3.yaml", cs::CalibFormat::OrbSlam3},
      {"t265_orbslam3_v0.yaml", cs::CalibFormat::OrbSlam3},
      {"vins/t265_stereo_config.yaml", cs::CalibFormat::VinsFusion},
  };
  return f;
}

double rigDifference(const cs::Rig& a, const cs::Rig& b) {
  double d = std::max((a.R - b.R).cwiseAbs().maxCoeff(), (a.t - b.t).cwiseAbs().maxCoeff());
  for (const auto& [ca, cb] : {std::pair{&a.cam0, &b.cam0}, std::pair{&a.cam1, &b.cam1}}) {
    REQUIRE(ca->model == cb->model);
    REQUIRE(ca->params.size() == cb->params.size());
    CHECK(ca->width == cb->width);
    CHECK(ca->height == cb->height);
    for (size_t i = 0; i < ca->params.size(); ++i) d = std::max(d, std::abs(ca->params[i] - cb->params[i]));
  }
  return d;
}

}  // namespace

TEST_CASE("the T265 calibration as Kalibr, Basalt, OpenCV YAML and XML: one rig to 1e-9") {
  const cs::Rig reference = cs::loadCalibration((dataDir() / "t265_camchain.yaml").string());
  for (const auto& [name, expected] : fixtures()) {
    CAPTURE(name);
    cs::CalibFormat format{};
    const cs::Rig rig = cs::loadCalibration((dataDir() / name).string(), &format);
    CHECK(format == expected);
    CHECK(rig.cam0.model == cs::CameraModel::KannalaBrandt4);
    CHECK(rigDifference(rig, reference) < 1e-9);
  }
  // The pose went through a product of transforms (rounding of the 15-digit files).
  cs::CalibHints size;  // t265_opencv_lists.yaml has none, as stereoCalibrate writes it
  size.width = 848;
  size.height = 800;
  for (const auto& [name, expected] : composedFixtures()) {
    CAPTURE(name);
    cs::CalibFormat format{};
    const cs::Rig rig = cs::loadCalibration((dataDir() / name).string(), &format, size);
    CHECK(format == expected);
    CHECK(rig.cam0.model == cs::CameraModel::KannalaBrandt4);
    CHECK(rigDifference(rig, reference) < 1e-9);
  }
  const std::string shared = cs::test::sharedData("t265/robot/camchain.yaml");
  if (shared.empty()) {
    MESSAGE("skipped the comparison with ../shared/data/t265: not present");
    return;
  }
  CHECK(rigDifference(cs::loadKalibr(shared), reference) == 0);
}

// The image shrunk by factor (factor x factor means), written as an 8-bit PNG at `to`.
static std::string shrunk(const std::string& from, const fs::path& to, int factor) {
  cs::writePngGray(to.string(), cs::test::shrink(cs::readPngGray(from), factor, true));
  return to.string();
}

TEST_CASE("curvestereo run gives the same depth with each T265 calibration file") {
  const std::string left = cs::test::sharedData("t265/robot/left.png");
  const std::string right = cs::test::sharedData("t265/robot/right.png");
  if (left.empty() || right.empty()) {
    MESSAGE("skipped: ../shared/data/t265 not present");
    return;
  }
  const fs::path dir = cs::test::tempDir("calib_t265_run");
  // A short solve on the CPU oracle at half the calibrated resolution (--scale-intrinsics):
  // the calibration enters through the fields and the calibration warp, which every warp and
  // level then uses, at any size; the full 848x800 took 4 x 10 s here, and 4 x 60 s under
  // the sanitizers. Under the sanitizers a quarter (212x200), for the same reason: the four
  // half-size runs were 65 s there.
  const std::string solver =
      " --backend cpu --preset realtime --warps 2 --pinhole 90 --equirect 256 --scale-intrinsics";
  const int factor = CS_SANITIZED ? 4 : 2;
  const std::string smallLeft = shrunk(left, dir / "left.png", factor),
                    smallRight = shrunk(right, dir / "right.png", factor);
  std::vector<cs::ImageF> depth, pinhole;
  for (const auto& [name, format] : fixtures()) {
    CAPTURE(name);
    const fs::path out = dir / name;
    const cs::test::CliOutcome o =
        cs::test::runCli(dir, "run --calib '" + (dataDir() / name).string() + "' '" + smallLeft + "' '" + smallRight +
                                  "' -o '" + out.string() + "'" + solver);
    REQUIRE_MESSAGE(o.exitCode == 0, o.err);
    depth.push_back(cs::readExr((out / "depth.exr").string()));
    pinhole.push_back(cs::readExr((out / "depth_pinhole.exr").string()));
    // The same bytes out: every number of the rig went in the same.
    if (format != cs::CalibFormat::Basalt)
      CHECK(cs::test::readFile(out / "depth.exr") == cs::test::readFile(dir / fixtures()[0].first / "depth.exr"));
  }
  // Basalt's pose goes through a quaternion (a rotation 1e-16 away): the same depth to float precision.
  for (size_t k = 1; k < depth.size(); ++k)
    for (const auto* maps : {&depth, &pinhole}) {
      const cs::ImageF &a = (*maps)[0], &b = (*maps)[k];
      REQUIRE(a.size() == b.size());
      size_t differ = 0, valid = 0;
      for (size_t i = 0; i < a.size(); ++i) {
        const float x = a.data[i], y = b.data[i];
        valid += std::isfinite(x);
        const bool same = std::isnan(x) ? std::isnan(y) : (x == y || std::abs(x - y) <= 1e-5f * x);
        differ += !same;
      }
      CHECK(valid > a.size() / 3);
      CHECK(differ == 0);
    }
}

// The command line of issue 18: `calib convert` / `calib show`, every calibration format
// for --calib, and run's --pinhole / --equirect / points.pcd outputs checked end to end
// against depth.exr and camera_info.yaml as a user would read them.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

#include "cli_util.hpp"
#include "curvestereo/depth_views.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/rig.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using cs::test::checkRefused;
using cs::test::CliOutcome;
using cs::test::runCli;

namespace {

fs::path dataDir() { return fs::path(cs::test::goldenDir()).parent_path() / "data"; }

// A small synthetic pair on disk: left.png, right.png, camchain.yaml.
fs::path writePair(const std::string& name) {
  const fs::path dir = cs::test::tempDir(name);
  const cs::synth::SynthPair pair = cs::test::smallSynthPair(96, "binocular", 0.12, 3);
  cs::writePngGray((dir / "left.png").string(), pair.left);
  cs::writePngGray((dir / "right.png").string(), pair.right);
  cs::saveKalibr(pair.rig, (dir / "camchain.yaml").string());
  return dir;
}

}  // namespace

TEST_CASE("calib convert: Kalibr -> Basalt -> OpenCV -> Kalibr, the format from the name or --format") {
  const fs::path dir = cs::test::tempDir("cli_calib_convert");
  const std::string t265 = (dataDir() / "t265_camchain.yaml").string();
  CliOutcome o = runCli(dir, "calib convert '" + t265 + "' calibration.json");
  REQUIRE_MESSAGE(o.exitCode == 0, o.err);
  CHECK(o.out.find("(kalibr) -> calibration.json (basalt)") != std::string::npos);
  o = runCli(dir, "calib convert calibration.json stereo.yml --format opencv");
  REQUIRE_MESSAGE(o.exitCode == 0, o.err);
  o = runCli(dir, "calib convert stereo.yml stereo.xml");
  REQUIRE_MESSAGE(o.exitCode == 0, o.err);
  o = runCli(dir, "calib convert stereo.xml camchain_back.yaml");
  REQUIRE_MESSAGE(o.exitCode == 0, o.err);
  const cs::Rig a = cs::loadCalibration(t265), b = cs::loadCalibration((dir / "camchain_back.yaml").string());
  CHECK(a.cam0.params == b.cam0.params);
  CHECK(a.cam1.params == b.cam1.params);
  CHECK((a.R - b.R).cwiseAbs().maxCoeff() < 1e-12);
  CHECK((a.t - b.t).cwiseAbs().maxCoeff() < 1e-12);

  o = runCli(dir, "calib show stereo.xml");
  CHECK(o.exitCode == 0);
  CHECK(o.out.find("format: opencv") != std::string::npos);
  CHECK(o.out.find("kannala-brandt4 848x800") != std::string::npos);
  CHECK(o.out.find("baseline 0.0641") != std::string::npos);
}

TEST_CASE("calib convert refuses with one line") {
  const fs::path dir = cs::test::tempDir("cli_calib_refuse");
  const std::string t265 = (dataDir() / "t265_camchain.yaml").string();
  checkRefused(runCli(dir, "calib convert '" + t265 + "' out.yaml"), "pass --format");
  checkRefused(runCli(dir, "calib convert '" + t265 + "' out.txt --format yaml"), "--format must be");
  checkRefused(runCli(dir, "calib convert '" + t265 + "'"), "IN and OUT", 2);
  checkRefused(runCli(dir, "calib frobnicate x"), "sub-command", 2);
  checkRefused(runCli(dir, "calib convert missing.json out.json"), "missing.json: cannot open file");
  cs::Rig ds = cs::loadCalibration(t265);
  ds.cam0 = ds.cam1 = cs::Camera::doubleSphere(848, 800, 158.3, 158.2, 423.5, 399.5, -0.18, 0.59);
  cs::saveBasalt(ds, (dir / "ds.json").string());
  checkRefused(runCli(dir, "calib convert ds.json stereo.xml"), "cannot represent the double-sphere");
  CHECK(!fs::exists(dir / "stereo.xml"));
}

TEST_CASE("run: points.pcd, --pinhole and --equirect, read back as a ROS user would") {
  const fs::path dir = writePair("cli_calib_views");
  // The Basalt form of the pair's calibration: --calib takes any format.
  CHECK(runCli(dir, "calib convert camchain.yaml calibration.json").exitCode == 0);
  const CliOutcome o = runCli(dir,
                              "run --calib calibration.json left.png right.png -o out --backend cpu --preset realtime "
                              "--pinhole 100,80x60 --equirect 128");
  REQUIRE_MESSAGE(o.exitCode == 0, o.err);
  CHECK(o.out.find("pinhole: 80x60") != std::string::npos);

  const cs::Rig rig = cs::loadCalibration((dir / "camchain.yaml").string());
  const cs::BuiltCamera cam0(rig.cam0);
  const cs::ImageF radial = cs::readExr((dir / "out/depth.exr").string());
  const cs::ImageF z = cs::readExr((dir / "out/depth_pinhole.exr").string());
  const cs::ImageF mm = cs::readPngGray((dir / "out/depth_pinhole.png").string());
  const YAML::Node info = YAML::LoadFile((dir / "out/camera_info.yaml").string());
  const auto K = info["camera_matrix"]["data"].as<std::vector<double>>();
  REQUIRE(K.size() == 9);
  REQUIRE(z.width == 80);
  REQUIRE(z.height == 60);
  CHECK(info["image_width"].as<int>() == 80);
  int checked = 0;
  for (int y = 0; y < z.height; ++y)
    for (int x = 0; x < z.width; ++x) {
      const cs::Vec3<double> ray((x - K[2]) / K[0], (y - K[5]) / K[4], 1.0);
      cs::Vec2<double> p;
      double expectedMm = std::isfinite(z(x, y)) ? std::round(double(z(x, y)) * 1000.0) : 0.0;
      if (expectedMm > 65535) expectedMm = 0;  // beyond 16 bits: invalid
      CHECK(std::lround(double(mm(x, y)) * 65535.0) == long(expectedMm));
      if (!std::isfinite(z(x, y))) continue;
      REQUIRE(cam0.project(ray, p));
      const float r = radial(int(std::floor(p.x() + 0.5)), int(std::floor(p.y() + 0.5)));
      CHECK(std::abs(double(z(x, y)) * ray.norm() - r) <= 2e-7 * r);  // the radial depth re-projected
      ++checked;
    }
  CHECK(checked > 1000);

  const cs::ImageF range = cs::readExr((dir / "out/range_equirect.exr").string());
  CHECK(range.width == 128);
  CHECK(range.height == 64);
  CHECK(std::isfinite(range(64, 32)));  // straight ahead
  CHECK(std::isnan(range(0, 32)));      // straight behind

  // points.pcd: organised like the image, each point at its pixel's radial depth.
  const std::string pcd = cs::test::readFile(dir / "out/points.pcd");
  const size_t data = pcd.find("DATA binary\n") + 12;
  REQUIRE(pcd.find("WIDTH 96\nHEIGHT 96\n") != std::string::npos);
  REQUIRE(pcd.size() == data + 96 * 96 * 12);
  int points = 0;
  for (size_t i = 0; i < radial.size(); ++i) {
    float xyz[3];
    std::memcpy(xyz, pcd.data() + data + 12 * i, 12);  // little-endian host, as the file
    if (!std::isfinite(radial.data[i])) {
      CHECK(std::isnan(xyz[0]));
      continue;
    }
    CHECK(std::sqrt(xyz[0] * xyz[0] + xyz[1] * xyz[1] + xyz[2] * xyz[2]) ==
          doctest::Approx(radial.data[i]).epsilon(1e-5));
    ++points;
  }
  CHECK(points > 1000);
}

TEST_CASE("run: bad --pinhole / --equirect / --sampling are refused before the solve") {
  const fs::path dir = writePair("cli_calib_view_errors");
  const std::string run = "run --calib camchain.yaml left.png right.png -o out --backend cpu ";
  checkRefused(runCli(dir, run + "--pinhole abc"), "--pinhole expects FOV[,WxH]");
  checkRefused(runCli(dir, run + "--pinhole 90,64"), "--pinhole expects FOV[,WxH]");
  checkRefused(runCli(dir, run + "--pinhole 185"), "1 to 179 degrees");
  checkRefused(runCli(dir, run + "--pinhole 90,0x10"), "pinhole image size");
  checkRefused(runCli(dir, run + "--equirect 101"), "--equirect expects an even width");
  checkRefused(runCli(dir, run + "--sampling cubic"), "--sampling expects nearest or bilinear");
  CHECK(!fs::exists(dir / "out"));
}

TEST_CASE("bench: per-stage medians and the sweep's total a frame") {
  const fs::path dir = writePair("cli_bench");
  const CliOutcome o = runCli(dir, "bench --calib camchain.yaml left.png right.png --runs 3 --backend cpu");
  CAPTURE(o.err);
  REQUIRE(o.exitCode == 0);
  // The pair's 8-bit files are timed as a camera's bytes, as Stereo takes them.
  CHECK(o.out.find("8-bit samples as stored") != std::string::npos);
  // Each row: name, median, min, max. The total's median lies between the largest
  // stage median and the sum of the stages' maxima (a frame's total sums its stages).
  std::istringstream lines(o.out);
  std::string line;
  double largestMedian = 0, sumOfMaxima = 0, total = -1;
  while (std::getline(lines, line)) {
    const bool isTotal = line.rfind("sweep, all stages", 0) == 0;
    if (line.rfind("sweep: ", 0) != 0 && !isTotal) continue;
    const std::string numbers = line.substr(20);
    double median = 0, lo = 0, hi = 0;
    REQUIRE(std::sscanf(numbers.c_str(), "%lf %lf %lf", &median, &lo, &hi) == 3);
    CHECK(lo <= median);
    CHECK(median <= hi);
    if (isTotal) {
      total = median;
    } else {
      largestMedian = std::max(largestMedian, median);
      sumOfMaxima += hi;
    }
  }
  CAPTURE(o.out);
  REQUIRE(total >= 0);
  CHECK(total >= largestMedian - 0.005);
  CHECK(total <= sumOfMaxima + 0.005);
}

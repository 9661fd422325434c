// Tests for the sequence metrics (metrics.hpp: maskedTau, flicker; docs/accuracy.md "How
// accuracy is measured", sequences) and `curvestereo eval --sequence` end to end on a tiny rendered
// sequence.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.hpp"
#include "curvestereo/camera.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/metrics.hpp"
#include "curvestereo/rig.hpp"
#include "synth/scene.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

namespace fs = std::filesystem;

constexpr int kSize = 96;
constexpr double kWall = 4.0;  // the world plane z = kWall that every view sees

Camera testCamera() { return synth::defaultFisheye(kSize); }

// Radial ground-truth depth of camera `cam` posed T_world_cam = pose, seeing only the plane
// z = kWall (world): +inf where the ray misses it, 0 outside the camera's valid region.
ImageF planeDepth(const Camera& cam, const Pose& pose) {
  const BuiltCamera built(cam);
  ImageF d(cam.width, cam.height, 0.f);
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      Vec3<double> ray;
      if (!built.unproject(Vec2<double>(x, y), ray)) continue;
      const Eigen::Vector3d dir = pose.R * ray;
      d(x, y) = dir.z() > 0.05 ? float((kWall - pose.t.z()) / dir.z()) : std::numeric_limits<float>::infinity();
    }
  return d;
}

// Two frames of camera 0: the second moved 0.25 m right and 0.3 m forward, turned 6 degrees.
struct TwoFrames {
  Camera cam = testCamera();
  Pose prevPose, pose;
  ImageF gtPrev, gt;
  Motion motion;  // prev -> current
  TwoFrames() {
    pose.R = Eigen::AngleAxisd(6.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
    pose.t = Eigen::Vector3d(0.25, 0.0, 0.3);
    gtPrev = planeDepth(cam, prevPose);
    gt = planeDepth(cam, pose);
    motion = motionBetween(prevPose, pose);
  }
};

ImageF scaled(const ImageF& depth, float factor) {
  ImageF out = depth;
  for (float& v : out.data)
    if (std::isfinite(v) && v > 0) v *= factor;
  return out;
}

// A block of pixels [x0, x0 + n) x [y0, y0 + n).
template <class F>
void forBlock(int x0, int y0, int n, F f) {
  for (int y = y0; y < y0 + n; ++y)
    for (int x = x0; x < x0 + n; ++x) f(x, y);
}

}  // namespace

TEST_CASE("flicker: zero when the estimates equal the ground truth") {
  const TwoFrames t;
  long long points = 0;
  CHECK(flicker(t.cam, t.gtPrev, t.gtPrev, t.gt, t.gt, nullptr, nullptr, t.motion, &points) == 0.0);
  CHECK(points > kSize * kSize / 4);
}

TEST_CASE("flicker: a relative error of +1 % in one frame and -1 % in the next is 0.02") {
  const TwoFrames t;
  long long points = 0;
  const double f =
      flicker(t.cam, scaled(t.gtPrev, 1.01f), t.gtPrev, scaled(t.gt, 0.99f), t.gt, nullptr, nullptr, t.motion, &points);
  CHECK(f == doctest::Approx(0.02).epsilon(1e-4));
  CHECK(points > kSize * kSize / 4);
  // The same error in both frames does not flicker.
  CHECK(flicker(t.cam, scaled(t.gtPrev, 1.03f), t.gtPrev, scaled(t.gt, 1.03f), t.gt, nullptr, nullptr, t.motion) ==
        doctest::Approx(0.0).epsilon(1e-6));
  // No point at all: NaN, and zero points.
  ImageF none(kSize, kSize, std::numeric_limits<float>::quiet_NaN());
  CHECK(std::isnan(flicker(t.cam, none, t.gtPrev, t.gt, t.gt, nullptr, nullptr, t.motion, &points)));
  CHECK(points == 0);
}

TEST_CASE("flicker: an error fixed to the surface does not flicker; the points follow the motion") {
  // e(x) depends on the world point x sees: the same point keeps its error from frame to
  // frame, so only the nearest-pixel lookup's rounding remains. Ignoring the motion (or
  // inverting it) pairs different points and flickers.
  const TwoFrames t;
  auto withWorldError = [&](const ImageF& gt, const Pose& pose) {
    const BuiltCamera cam(t.cam);
    ImageF est = gt;
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        Vec3<double> ray;
        if (!std::isfinite(gt(x, y)) || gt(x, y) <= 0 || !cam.unproject(Vec2<double>(x, y), ray)) continue;
        const Eigen::Vector3d X = pose.R * (double(gt(x, y)) * ray) + pose.t;
        est(x, y) = gt(x, y) * float(1.0 + 0.1 * std::sin(1.5 * X.x()) * std::cos(1.5 * X.y()));
      }
    return est;
  };
  const ImageF estPrev = withWorldError(t.gtPrev, t.prevPose), est = withWorldError(t.gt, t.pose);
  long long points = 0, pointsStill = 0, pointsInverse = 0;
  const double following = flicker(t.cam, estPrev, t.gtPrev, est, t.gt, nullptr, nullptr, t.motion, &points);
  const double still = flicker(t.cam, estPrev, t.gtPrev, est, t.gt, nullptr, nullptr, Motion{}, &pointsStill);
  const double inverse =
      flicker(t.cam, estPrev, t.gtPrev, est, t.gt, nullptr, nullptr, motionBetween(t.pose, t.prevPose), &pointsInverse);
  MESSAGE("following " << following << " (" << points << " points), still " << still << " (" << pointsStill
                       << "), inverse " << inverse << " (" << pointsInverse << ")");
  CHECK(following < 0.5 * still);
  CHECK(following < 0.5 * inverse);
}

TEST_CASE("flicker: points occluded in the previous frame are skipped") {
  const TwoFrames t;
  long long clearPoints = 0, points = 0;
  flicker(t.cam, scaled(t.gtPrev, 1.01f), t.gtPrev, scaled(t.gt, 0.99f), t.gt, nullptr, nullptr, t.motion,
          &clearPoints);
  // An occluder 1 m from camera 0 in the previous frame only, its estimate 50 % off: the
  // points of the plane behind it are not seen in frame k-1 and must not count.
  ImageF gtPrev = t.gtPrev, estPrev = scaled(t.gtPrev, 1.01f);
  forBlock(kSize / 2 - 12, kSize / 2 - 12, 24, [&](int x, int y) {
    gtPrev(x, y) = 1.0f;
    estPrev(x, y) = 1.5f;
  });
  const double f = flicker(t.cam, estPrev, gtPrev, scaled(t.gt, 0.99f), t.gt, nullptr, nullptr, t.motion, &points);
  CHECK(f == doctest::Approx(0.02).epsilon(1e-4));
  CHECK(points < clearPoints - 300);
  // Pixels without ground truth (sky, outside the image circle) in frame k count nowhere.
  ImageF gt = t.gt, est = scaled(t.gt, 0.99f);
  forBlock(0, kSize / 2, kSize / 2, [&](int x, int y) { gt(x, y) = std::numeric_limits<float>::infinity(); });
  CHECK(flicker(t.cam, scaled(t.gtPrev, 1.01f), t.gtPrev, est, gt, nullptr, nullptr, t.motion, &points) ==
        doctest::Approx(0.02).epsilon(1e-4));
  CHECK(points < clearPoints - 300);
}

TEST_CASE("flicker: pixels of the moving object (either frame's mover mask) are left out") {
  const TwoFrames t;
  const ImageF estPrev = scaled(t.gtPrev, 1.01f), est = scaled(t.gt, 0.99f);
  long long clearPoints = 0, points = 0;
  flicker(t.cam, estPrev, t.gtPrev, est, t.gt, nullptr, nullptr, t.motion, &clearPoints);

  // Frame k: the mover's pixels are 40 % off.
  ImageU8 mover(kSize, kSize, 0);
  ImageF estMoving = est;
  forBlock(30, 30, 20, [&](int x, int y) {
    mover(x, y) = 255;
    estMoving(x, y) = t.gt(x, y) * 1.4f;
  });
  CHECK(flicker(t.cam, estPrev, t.gtPrev, estMoving, t.gt, nullptr, &mover, t.motion, &points) ==
        doctest::Approx(0.02).epsilon(1e-4));
  CHECK(points == clearPoints - 400);
  CHECK(flicker(t.cam, estPrev, t.gtPrev, estMoving, t.gt, nullptr, nullptr, t.motion) > 0.03);  // the mask matters

  // Frame k-1: the same in the previous frame's mask.
  ImageU8 moverPrev(kSize, kSize, 0);
  ImageF estPrevMoving = estPrev;
  forBlock(40, 40, 20, [&](int x, int y) {
    moverPrev(x, y) = 1;
    estPrevMoving(x, y) = t.gtPrev(x, y) * 0.6f;
  });
  CHECK(flicker(t.cam, estPrevMoving, t.gtPrev, est, t.gt, &moverPrev, nullptr, t.motion, &points) ==
        doctest::Approx(0.02).epsilon(1e-4));
  CHECK(points < clearPoints - 200);
  CHECK(flicker(t.cam, estPrevMoving, t.gtPrev, est, t.gt, nullptr, nullptr, t.motion) > 0.03);
}

TEST_CASE("flicker: an estimate far off or at infinity counts as a relative error of 1") {
  const TwoFrames t;
  ImageF est = t.gt;
  for (float& v : est.data)
    if (std::isfinite(v) && v > 0) v = std::numeric_limits<float>::infinity();
  CHECK(flicker(t.cam, t.gtPrev, t.gtPrev, est, t.gt, nullptr, nullptr, t.motion) == doctest::Approx(1.0));
  CHECK(flicker(t.cam, t.gtPrev, t.gtPrev, scaled(t.gt, 5.f), t.gt, nullptr, nullptr, t.motion) ==
        doctest::Approx(1.0));
  CHECK_THROWS_AS(flicker(t.cam, ImageF(8, 8), t.gtPrev, t.gt, t.gt, nullptr, nullptr, t.motion), Error);
}

TEST_CASE("maskedTau: the share of the mask's evaluated pixels over k, a missing estimate an error") {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  ImageF error(4, 2);
  error.data = {0.5f, 2.f, inf, nan, 3.f, 0.2f, 0.9f, 5.f};
  ImageU8 mask(4, 2);
  mask.data = {1, 1, 1, 1, 0, 0, 1, 0};
  long long n = 0;
  CHECK(maskedTau(error, mask, 1.0, &n) == doctest::Approx(50.0));  // 2 of 4 (0.5, 2, inf, 0.9)
  CHECK(n == 4);
  CHECK(std::isnan(maskedTau(error, ImageU8(4, 2, 0), 1.0, &n)));
  CHECK(n == 0);
  CHECK_THROWS_AS(maskedTau(error, ImageU8(2, 2, 1), 1.0), Error);
}

// --- eval --sequence end to end ---

namespace {

void writeText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

// An ASL folder as ../shared/data/sequences holds them: a 64 x 64 rendered scene, the rig
// moving 4 cm forward per frame; mover0 marks a block (static here: it only feeds the figure).
void writeTinySequence(const fs::path& dir, int frames, int size = 64) {
  const synth::SynthPair p = test::smallSynthPair(size, "binocular", 0.12, 5);
  for (const char* sub : {"cam0", "cam1", "depth0", "depth1", "mover0"})
    fs::create_directories(dir / "mav0" / sub / "data");
  saveKalibr(p.rig, (dir / "camchain.yaml").string());
  const fs::path mav0 = dir / "mav0";
  std::string csvImg = "#timestamp [ns],filename\n", csvExr = csvImg, poses = "#timestamp [ns],px,py,pz,qx,qy,qz,qw\n";
  synth::RenderOptions options;
  options.samplesPerAxis = 1;
  for (int k = 0; k < frames; ++k) {
    const int64_t t = 1000000000000 + int64_t(k) * 33333333;
    const std::string ts = std::to_string(t);
    const Eigen::Vector3d step = p.pose0.rotation * Eigen::Vector3d(0, 0, 0.04 * k);
    synth::Pose pose0 = p.pose0, pose1 = p.pose1;
    pose0.centre += step;
    pose1.centre += step;
    ImageF image, depth;
    synth::renderView(p.scene, p.rig.cam0, pose0, options, image, depth);
    writePngGray((mav0 / "cam0/data" / (ts + ".png")).string(), image);
    writeExr((mav0 / "depth0/data" / (ts + ".exr")).string(), depth);
    synth::renderView(p.scene, p.rig.cam1, pose1, options, image, depth);
    writePngGray((mav0 / "cam1/data" / (ts + ".png")).string(), image);
    writeExr((mav0 / "depth1/data" / (ts + ".exr")).string(), depth);
    ImageF mover(size, size, 0.f);
    forBlock(24, 24, 8, [&](int x, int y) { mover(x, y) = 1.f; });
    writePngGray((mav0 / "mover0/data" / (ts + ".png")).string(), mover);
    csvImg += ts + "," + ts + ".png\n";
    csvExr += ts + "," + ts + ".exr\n";
    const Eigen::Quaterniond q(pose0.rotation);
    std::ostringstream line;
    line.precision(17);
    line << t << "," << pose0.centre.x() << "," << pose0.centre.y() << "," << pose0.centre.z() << "," << q.x() << ","
         << q.y() << "," << q.z() << "," << q.w() << "\n";
    poses += line.str();
  }
  for (const char* cam : {"cam0", "cam1", "mover0"}) writeText(mav0 / cam / "data.csv", csvImg);
  for (const char* d : {"depth0", "depth1"}) writeText(mav0 / d / "data.csv", csvExr);
  writeText(dir / "poses_cam0.csv", poses);
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream s(text);
  for (std::string l; std::getline(s, l);) out.push_back(l);
  return out;
}

// Field i of a CSV line.
std::string field(const std::string& line, size_t i) {
  std::istringstream s(line);
  std::string f;
  for (size_t k = 0; k <= i; ++k) std::getline(s, f, ',');
  return f;
}

}  // namespace

TEST_CASE("eval --sequence: cold and warm runs of a tiny rendered sequence, tables and files") {
  const fs::path dir = test::tempDir("eval_sequence");
  writeTinySequence(dir / "seq", 3);
  const test::CliOutcome o =
      test::runCli(dir, "eval --sequence seq --compare=on --backend cpu --min-width 16 --csv seq.csv --md seq.md");
  REQUIRE_MESSAGE(o.exitCode == 0, o.err);
  CHECK(o.out.find("judged seq: flicker warm/cold") != std::string::npos);
  CHECK(o.out.find("summary seq cold:") != std::string::npos);
  CHECK(o.out.find("summary seq warm:") != std::string::npos);
  CHECK(o.err.find("fps") != std::string::npos);

  const std::vector<std::string> csv = lines(test::readFile(dir / "seq.csv"));
  REQUIRE(csv.size() == 1 + 2 * (3 + 1));  // header, then 3 frames and a mean per mode
  CHECK(field(csv[0], 11) == "flicker");
  CHECK(field(csv[1], 1) == "cold");
  CHECK(field(csv[1], 4) == "cold");
  CHECK(field(csv[1], 11).empty());  // no previous frame
  for (int row : {2, 3, 6, 7}) {
    const double f = std::stod(field(csv[size_t(row)], 11));
    CHECK(f >= 0.0);
    CHECK(f < 0.5);
    CHECK(std::stoll(field(csv[size_t(row)], 12)) > 500);  // flicker points
  }
  CHECK(std::stoll(field(csv[1], 10)) > 0);  // mover pixels evaluated
  CHECK(field(csv[4], 2) == "mean");
  CHECK(field(csv[4], 4) == "0/3/0");  // cold: every frame cold
  CHECK(field(csv[5], 1) == "warm");
  CHECK(field(csv[5], 4) == "cold");  // the first frame is always cold
  // 64 px has levels down to 16 px with --min-width 16: the band sweep, so warm frames.
  CHECK(field(csv[6], 4) != "cold");
  CHECK(field(csv[7], 4) != "cold");
  CHECK(test::readFile(dir / "seq.md").find("flicker warm/cold") != std::string::npos);

  // One mode and --frames.
  const test::CliOutcome cold = test::runCli(dir, "eval --sequence seq --frames 2 --backend cpu --cold");
  REQUIRE_MESSAGE(cold.exitCode == 0, cold.err);
  CHECK(cold.out.find("frames warm/cold/redone 0/2/0") != std::string::npos);
}

TEST_CASE("eval --sequence: one-line errors naming the problem") {
  const fs::path dir = test::tempDir("eval_sequence_errors");
  writeTinySequence(dir / "seq", 2);
  // Exit 1 for the inputs, 2 for a malformed command line.
  auto refused = [&](const std::string& args, const std::string& expect, int exitCode = 1) {
    const test::CliOutcome o = test::runCli(dir, args);
    CHECK(o.exitCode == exitCode);
    CHECK_MESSAGE(o.err.find(expect) != std::string::npos, o.err);
    CHECK(lines(o.err).size() <= 3);  // the notes on the folder, then one line of error
  };
  refused("eval --sequence seq --cold=on --compare=on", "exclude each other", 2);
  refused("eval --sequence seq --methods all", "--methods is for pair folders", 2);
  refused("eval pairdir --cold=on", "--cold is for --sequence", 2);
  refused("eval --sequence seq --cold=maybe", "--cold takes no value", 2);
  // A frame's ground truth missing: named before any solving.
  fs::remove(dir / "seq/mav0/depth0/data/1000033333333.exr");
  refused("eval --sequence seq --backend cpu", "frame 1: missing depth0 file");
  fs::remove_all(dir / "seq/mav0/depth0");
  refused("eval --sequence seq --backend cpu", "no mav0/depth0");
  fs::remove(dir / "seq/camchain.yaml");
  refused("eval --sequence seq --backend cpu", "has no camchain.yaml");
  refused("eval --sequence nowhere", "nowhere");
}

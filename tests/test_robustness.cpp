// Numerical robustness and resource limits of the public API (issue 6): degenerate images,
// non-finite input, forward motion, lenses wider than 180 degrees, frames too large for
// memory. The contract: pixels marked valid carry finite disparity and warp and a radial
// depth that is finite and positive or +inf (zero disparity: a point at infinity);
// pixels not marked valid carry NaN everywhere. Bad input is a cs::Error, never a crash.
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "cpu_backend.hpp"
#include "curvestereo/stereo.hpp"
#include "golden_cases.hpp"  // hash01
#include "synth/scene.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

constexpr double kPi = 3.14159265358979323846;

// 2x2 samples per pixel; one under the sanitizers, where rendering was half of this suite's
// time: the contract holds for any image (the degenerate ones below included), and the
// masks and depth truth come from the pixel-centre rays either way.
synth::SynthPair render(const Camera& camera, const std::string& motion, double baseline, double maxFovDeg,
                        uint32_t seed = 7) {
  synth::SynthConfig cfg;
  cfg.camera = camera;
  cfg.motion = motion;
  cfg.baseline = baseline;
  cfg.seed = seed;
  cfg.nearest = 1.5;
  cfg.samplesPerAxis = CS_SANITIZED ? 1 : 2;
  cfg.maxFovDeg = maxFovDeg;
  return synth::renderPair(cfg);
}

// The 96 px binocular pair the first cases share, rendered once.
const synth::SynthPair& binocularPair() {
  static const synth::SynthPair pair = render(synth::defaultFisheye(96), "binocular", 0.12, 180);
  return pair;
}

// The realtime preset, with short solves under the sanitizers (test_util.hpp): the output
// contract and the masks checked here hold after any number of warps.
Params fast(double maxFovDeg = 180) {
  Params p = preset("realtime");
  p.maxFovDeg = maxFovDeg;
  p.warps = test::shortUnderSanitizers(p.warps);
  return p;
}

struct Census {
  long long valid = 0, infinite = 0, behind = 0;
};

// The output contract above, pixel by pixel; counts what it saw.
Census checkContract(const DepthResult& r, const BuiltCamera* cam0 = nullptr) {
  Census c;
  long long broken = 0;
  for (int y = 0; y < r.valid.height; ++y)
    for (int x = 0; x < r.valid.width; ++x) {
      const size_t i = size_t(y) * size_t(r.valid.width) + size_t(x);
      const float d = r.depth.radial.data[i];
      const Point3f& p = r.depth.points.data[i];
      if (!r.valid.data[i]) {
        broken += !std::isnan(d) || !std::isnan(r.disparity.data[i]) || !std::isnan(r.warp.data[i].x) ||
                  !std::isnan(r.warp.data[i].y) || !std::isnan(r.depth.z.data[i]) || !std::isnan(p.x);
        continue;
      }
      ++c.valid;
      broken += !std::isfinite(r.disparity.data[i]) || !std::isfinite(r.warp.data[i].x) ||
                !std::isfinite(r.warp.data[i].y) || std::isnan(d) || !(d > 0.f) || std::isnan(r.depth.z.data[i]);
      if (std::isinf(d)) {
        ++c.infinite;
        broken += d < 0.f;
      } else {
        broken +=
            !std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !std::isfinite(r.depth.z.data[i]);
      }
      if (cam0) {
        Vec3<double> ray;
        if (cam0->unproject(Vec2<double>(x, y), ray) && ray.z() < -0.05) ++c.behind;
      }
    }
  CHECK(broken == 0);
  return c;
}

// Deterministic noise, the same on every platform.
ImageF noise(int w, int h, uint32_t seed) {
  ImageF img(w, h);
  for (size_t i = 0; i < img.size(); ++i) img.data[i] = golden::hash01(uint32_t(i) + seed * 0x9e3779b9u);
  return img;
}

}  // namespace

TEST_CASE("degenerate images: constant, black, saturated, noise, one side blank") {
  const synth::SynthPair& pair = binocularPair();
  Stereo stereo(pair.rig, fast(), "cpu");
  const int w = pair.left.width, h = pair.left.height;
  const ImageF black(w, h, 0.f), grey(w, h, 0.5f), white(w, h, 1.f);
  ImageF clipped = pair.left;  // a saturated scene: most of it clipped at 1
  for (float& v : clipped.data) v = std::min(1.f, 4.f * v);
  struct Case {
    const char* name;
    const ImageF& left;
    const ImageF& right;
  };
  const ImageF n0 = noise(w, h, 1), n1 = noise(w, h, 2);
  for (const Case& c : {Case{"black", black, black}, Case{"constant", grey, grey}, Case{"saturated", white, white},
                        Case{"clipped", clipped, clipped}, Case{"noise", n0, n1}, Case{"left black", black, pair.right},
                        Case{"right white", pair.left, white}}) {
    const std::string name = c.name;
    CAPTURE(name);
    const Census census = checkContract(stereo.compute(c.left, c.right));
    CHECK(census.valid > 0);  // the mask depends on the rig, not the content
  }
}

TEST_CASE("non-finite pixels are refused by the library with cs::Error") {
  const synth::SynthPair& pair = binocularPair();
  Stereo stereo(pair.rig, fast(), "cpu");
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                    -std::numeric_limits<float>::infinity()}) {
    ImageF left = pair.left, right = pair.right;
    left(3, 70) = bad;
    CHECK_THROWS_WITH_AS(stereo.compute(left, pair.right), "left image contains NaN or infinite pixels", Error);
    right(95, 95) = bad;
    CHECK_THROWS_WITH_AS(stereo.compute(pair.left, right), "right image contains NaN or infinite pixels", Error);
  }
  // Out-of-range but finite values are not an error; the output keeps its contract.
  ImageF loud = pair.left;
  for (float& v : loud.data) v = 1e30f * (v - 0.5f);
  checkContract(stereo.compute(loud, pair.right));
  // An empty image is a size mismatch, not a crash.
  CHECK_THROWS_WITH_AS(stereo.compute(ImageF(), pair.right), doctest::Contains("0x0"), Error);
}

TEST_CASE("forward motion: the epipole is inside the image and masked; the rest keeps the contract") {
  const synth::SynthPair pair = render(synth::defaultFisheye(96), "forward", 0.3, 180);
  Stereo stereo(pair.rig, fast(), "cpu");
  const DepthResult r = stereo.compute(pair.left, pair.right);
  const Census c = checkContract(r);
  CHECK(c.valid > 2000);
  const BuiltCamera cam0(pair.rig.cam0);
  for (double sign : {-1.0, 1.0}) {  // the focus of expansion and of contraction
    Vec2<double> epipole;
    if (!cam0.project(Vec3<double>(sign * pair.rig.tPrime().normalized()), epipole)) continue;
    if (!cam0.inImage(epipole)) continue;
    CHECK(r.valid(int(std::lround(epipole.x())), int(std::lround(epipole.y()))) == 0);
  }
  // Pure forward motion along the optical axis: epipole exactly at the principal point.
  stereo.setPose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, -0.25));
  const DepthResult axial = stereo.compute(pair.left, pair.right);
  checkContract(axial);
  CHECK(axial.valid(48, 48) == 0);
}

TEST_CASE("fields of view beyond 180 degrees: 220-degree Kannala-Brandt and 195-degree double sphere") {
  const double f = 0.5 * 96 / (110.0 * kPi / 180.0);
  const Camera kb220 = Camera::kannalaBrandt4(96, 96, f, f, 47.5, 47.5);
  const Camera ds195 = Camera::doubleSphere(512, 512, 158.3, 158.2, 254.9, 256.9, -0.18, 0.59).scaled(96 / 512.0);
  struct Case {
    const char* name;
    Camera camera;
    double fov;  // rendered and solved with this maxFovDeg (0: the model's own region)
  };
  for (const Case& c : {Case{"kb 220, maxFov 220", kb220, 220}, Case{"kb 220, maxFov 0", kb220, 0},
                        Case{"ds 195, maxFov 0", ds195, 0}}) {
    const std::string name = c.name;
    CAPTURE(name);
    for (const std::string motion : {"binocular", "forward"}) {
      CAPTURE(motion);
      const synth::SynthPair pair = render(c.camera, motion, 0.2, c.fov);
      Stereo stereo(pair.rig, fast(c.fov), "cpu");
      const BuiltCamera cam0(pair.rig.cam0);
      const Census census = checkContract(stereo.compute(pair.left, pair.right), &cam0);
      CHECK(census.valid > 1000);
      MESSAGE(name << " " << motion << ": " << census.valid << " valid, " << census.behind
                   << " behind the image plane, " << census.infinite << " at infinity");
      if (motion == "binocular") CHECK(census.behind > 0);  // the solve really reaches past 90 deg
    }
  }
}

TEST_CASE("bad rigs are refused by Stereo with one-line errors") {
  const Camera cam = synth::defaultFisheye(64);
  Rig rig;
  rig.cam0 = rig.cam1 = cam;
  rig.t = Eigen::Vector3d(-0.1, 0, 0);
  auto refuse = [&](const Rig& bad, const char* needle) {
    const std::string expected = needle;
    CAPTURE(expected);
    try {
      Stereo stereo(bad, fast(), "cpu");
      FAIL("no error");
    } catch (const Error& e) {
      const std::string what = e.what();
      CHECK(what.find(needle) != std::string::npos);
      CHECK(what.find('\n') == std::string::npos);
      MESSAGE(what);
    }
  };
  Rig r = rig;
  r.cam0.params[0] = std::numeric_limits<double>::quiet_NaN();
  refuse(r, "fx is not finite");
  r = rig, r.cam1.params[1] = -200;
  refuse(r, "not positive");
  r = rig, r.cam0.params[0] = 1e300;
  refuse(r, "fx = 1e+300 px is absurd");
  r = rig, r.cam0.params[2] = 1e6;
  refuse(r, "far outside the image");
  r = rig, r.R = 1.01 * Eigen::Matrix3d::Identity();
  refuse(r, "not a rotation");
  r = rig, r.R = Eigen::Vector3d(1, 1, -1).asDiagonal();  // a reflection: orthogonal, det = -1
  refuse(r, "not a rotation");
  r = rig, r.t = Eigen::Vector3d(1e-8, 0, 0);
  refuse(r, "zero baseline");
  r = rig, r.t = Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0, 0);
  refuse(r, "non-finite");
  r = rig, r.cam0 = r.cam1 = cam.scaled(12 / 64.0);
  refuse(r, "too small");
  r = rig, r.cam1 = cam.scaled(12 / 64.0);  // either camera
  refuse(r, "too small");
  r = rig, r.cam0 = r.cam1 = cam.scaled(40000 / 64.0);
  refuse(r, "too large");
}

TEST_CASE("a frame too large for memory is an error naming its size, before anything is allocated") {
  const unsigned long long memory = cpu::usableMemoryBytes();
  const Camera huge = synth::defaultFisheye(64).scaled(32768 / 64.0);
  Rig rig;
  rig.cam0 = rig.cam1 = huge;
  rig.t = Eigen::Vector3d(-0.1, 0, 0);
  // 32768 x 32768 needs about 220 GB of buffers; skip where the machine really has that.
  if (memory == 0 || memory > 200ull << 30) {
    MESSAGE("skipped: this machine reports " << memory << " bytes of memory");
    return;
  }
  try {
    Stereo stereo(rig, fast(), "cpu");
    FAIL("no error");
  } catch (const Error& e) {
    const std::string what = e.what();
    MESSAGE(what);
    CHECK(what.find("out of memory") != std::string::npos);
    CHECK(what.find("32768x32768") != std::string::npos);
    CHECK(what.find("bytes") != std::string::npos);
  }
  // The backend on its own refuses a buffer beyond memory, naming its size.
  cpu::CpuBackend backend;
  CHECK_THROWS_WITH_AS(backend.create(32768, 32768, 64), doctest::Contains("32768x32768x64"), Error);
  CHECK(backend.create(16, 16, 1).count() == 256);  // and stays usable
}

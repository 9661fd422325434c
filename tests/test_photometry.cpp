// The camera (photometric) model of synthetic pairs (tools/synth/photometry.hpp): off it
// changes nothing; each stage does what it says (exposure, vignetting, gain, noise,
// blur, response, quantisation); the noise is reproducible per seed; the ground truth
// is untouched; the CLI writes what it promises; and a T265-like pair still solves.
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "curvestereo/image_io.hpp"
#include "curvestereo/metrics.hpp"
#include "curvestereo/stereo.hpp"
#include "synth/photometry.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using namespace cs;
using namespace cs::synth;

namespace {

// A pair of flat images (every pixel `level`, all of it valid) on the default fisheye:
// what a stage does shows without scene texture.
SynthPair flatPair(int size, float level) {
  SynthPair p;
  p.rig.cam0 = p.rig.cam1 = defaultFisheye(size);
  p.left = p.right = ImageF(size, size, level);
  p.depthLeft = p.depthRight = ImageF(size, size, 1.f);
  return p;
}

// A model with every stage off except what the test sets; 16 bits, so quantisation
// (1/65535) does not hide what is measured.
CameraPhotometry bare() {
  CameraPhotometry m;
  m.bits = 16;
  return m;
}

double median(std::vector<float> v) {
  auto mid = v.begin() + (v.size() - 1) / 2;
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

std::vector<float> validValues(const ImageF& image, const ImageF& depth) {
  std::vector<float> v;
  for (size_t i = 0; i < image.size(); ++i)
    if (depth.data[i] > 0.f) v.push_back(image.data[i]);
  return v;
}

struct Moments {
  double mean = 0.0, stddev = 0.0;
};

Moments moments(const ImageF& image) {
  double sum = 0.0, sq = 0.0;
  for (float v : image.data) sum += v, sq += double(v) * v;
  const double n = double(image.size()), mean = sum / n;
  return {mean, std::sqrt(std::max(0.0, sq / n - mean * mean))};
}

// ---- the command line

fs::path cliPath() { return fs::read_symlink("/proc/self/exe").parent_path().parent_path() / "tools" / "curvestereo"; }

std::string readAll(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

// Runs `curvestereo args` in dir; returns the exit code, stdout into *out.
int runCli(const fs::path& dir, const std::string& args, std::string* out = nullptr) {
  const std::string cmd =
      "cd '" + dir.string() + "' && '" + cliPath().string() + "' " + args + " > stdout.txt 2> stderr.txt";
  const int status = std::system(cmd.c_str());
  if (out) *out = readAll(dir / "stdout.txt");
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace

TEST_CASE("photometry: off is the identity, bit for bit") {
  const SynthPair clean = test::smallSynthPair(64, "binocular", 0.12, 2);
  CHECK(!photometryProfile("none").enabled());
  CHECK(!CameraPhotometry().enabled());
  SynthPair p = clean;
  CHECK(applyPhotometry(photometryProfile("none"), p) == 1.0);
  CHECK(p.left.data == clean.left.data);
  CHECK(p.right.data == clean.right.data);
  // The t265 profile with every stage set back to its identity value is off too.
  CameraPhotometry m = photometryProfile("t265");
  m.exposure = m.blur = m.shot = m.read = 0.0;
  m.left.rim = m.right.rim = m.right.gain = 1.0;
  CHECK(!m.enabled());
  applyPhotometry(m, p);
  CHECK(p.left.data == clean.left.data);
  m.blur = 0.1;  // any one stage turns it on
  CHECK(m.enabled());
}

TEST_CASE("photometry: the t265 profile holds mid-range T265 values") {
  const CameraPhotometry m = photometryProfile("t265");
  CHECK(m.enabled());
  CHECK_NOTHROW(m.validate());
  CHECK(m.exposure == 0.2);
  CHECK(m.left.rim == 0.35);
  CHECK(m.right.rim == 0.35);
  CHECK(m.left.gain == 1.0);
  CHECK(m.right.gain == 1.06);
  CHECK(m.read == 1.5);
  CHECK(m.shot == 0.08);
  CHECK(m.blur == 0.6);
  CHECK(m.bits == 8);
  CHECK(m.vignetteMode == VignetteMode::Radius);
  CHECK_THROWS_WITH_AS(photometryProfile("d435"), doctest::Contains("unknown camera model 'd435'"), Error);
}

TEST_CASE("photometry: exposure puts the left median inside the image circle at the target") {
  const SynthPair clean = test::smallSynthPair(128, "binocular", 0.12, 4);
  for (double target : {0.1, 0.2, 0.3}) {
    CameraPhotometry m = bare();
    m.exposure = target;
    SynthPair p = clean;
    const double scale = applyPhotometry(m, p);
    CHECK(scale > 0.0);
    CHECK(std::abs(median(validValues(p.left, p.depthLeft)) - target) < 1e-4);
    // The whole t265 chain (vignetting first, then blur, noise, 8 bits): within a grey level.
    m = photometryProfile("t265");
    m.exposure = target;
    p = clean;
    applyPhotometry(m, p);
    CHECK(std::abs(median(validValues(p.left, p.depthLeft)) - target) <= 1.0 / 255.0);
  }
}

TEST_CASE("photometry: vignetting falls to `rim` at half the image side") {
  const int size = 201;  // principal point (100, 100) on a pixel centre
  const double rim = 0.4, c = 100.0, half = 100.5;
  CameraPhotometry m = bare();
  m.left.rim = m.right.rim = rim;
  SynthPair p = flatPair(size, 0.5f);
  applyPhotometry(m, p);
  CHECK(p.left(100, 100) == doctest::Approx(0.5).epsilon(1e-4));
  for (int x : {100, 150, 180, 200}) {
    const double r = (x - c) / half;
    CHECK(p.left(x, 100) == doctest::Approx(0.5 * (1.0 - (1.0 - rim) * r * r)).epsilon(1e-4));
  }
  // Rim / centre, at r = 1 (between pixels 200 and 201 of a 201 px image: extrapolated
  // from the exact quadratic through the centre and pixel 200).
  const double r200 = 100.0 / half, drop = (p.left(100, 100) - p.left(200, 100)) / (r200 * r200);
  CHECK((p.left(100, 100) - drop) / p.left(100, 100) == doctest::Approx(rim).epsilon(1e-3));

  // Angle mode: the same for the equidistant 180 deg default lens (angle = radius * 90 deg) ...
  const ImageF byRadius = vignetting(defaultFisheye(96), rim, VignetteMode::Radius);
  const ImageF byAngle = vignetting(defaultFisheye(96), rim, VignetteMode::Angle);
  for (size_t i = 0; i < byRadius.size(); ++i) REQUIRE(std::abs(byRadius.data[i] - byAngle.data[i]) < 1e-5f);
  // ... and it follows the lens for another model: rim exactly at 90 deg off axis.
  // (TUM-VI-like double sphere, ~195 deg, with 90 deg at x = 155 of 160.)
  const Camera ds = Camera::doubleSphere(160, 160, 39.6, 39.6, 79.5, 79.5, -0.18, 0.59);
  const ImageF angle = vignetting(ds, rim, VignetteMode::Angle);
  Vec2<double> at90;
  const BuiltCamera built(ds);
  REQUIRE(built.project(Vec3<double>(1.0, 0.0, 0.0), at90));
  const int x90 = int(std::lround(at90.x())), y = 79;
  REQUIRE(angle.inside(x90, y));
  Vec3<double> ray;
  REQUIRE(built.unproject(Vec2<double>(x90, y), ray));
  const double s = std::acos(ray.normalized().z()) / (0.5 * M_PI);
  CHECK(std::abs(s - 1.0) < 0.02);
  CHECK(angle(x90, y) == doctest::Approx(1.0 - (1.0 - rim) * s * s).epsilon(1e-5));
  CHECK(angle(x90, y) == doctest::Approx(rim).epsilon(0.05));
  // The radius mode would put the rim elsewhere on this lens (r = 75 / 80 here).
  CHECK(std::abs(vignetting(ds, rim, VignetteMode::Radius)(x90, y) - angle(x90, y)) > 0.02);
}

TEST_CASE("photometry: per-camera gain, offset and the response curve") {
  CameraPhotometry m = bare();
  m.right.gain = 1.06;
  SynthPair p = flatPair(32, 0.3f);
  applyPhotometry(m, p);
  CHECK(p.right(5, 5) / p.left(5, 5) == doctest::Approx(1.06).epsilon(1e-4));
  // The gain ratio survives exposure and vignetting (both shared by the two cameras).
  m = photometryProfile("t265");
  m.shot = m.read = 0.0;
  m.bits = 16;
  p = flatPair(64, 0.5f);
  applyPhotometry(m, p);
  CHECK(p.right(32, 32) / p.left(32, 32) == doctest::Approx(1.06).epsilon(1e-3));

  m = bare();
  m.left.offset = 0.05;
  m.right.offset = -0.05;
  m.gamma = 2.0;
  p = flatPair(8, 0.2f);
  applyPhotometry(m, p);
  CHECK(p.left(1, 1) == doctest::Approx(std::sqrt(0.25)).epsilon(1e-4));   // (0.2 + 0.05)^(1/2)
  CHECK(p.right(1, 1) == doctest::Approx(std::sqrt(0.15)).epsilon(1e-4));  // (0.2 - 0.05)^(1/2)
}

TEST_CASE("photometry: noise has variance shot * I + read^2 in 8-bit grey levels") {
  CameraPhotometry m = bare();
  m.shot = 0.08;
  m.read = 1.5;
  for (int bits : {16, 8})
    for (float level : {0.05f, 0.2f, 0.6f}) {
      m.bits = bits;
      SynthPair p = flatPair(256, level);
      applyPhotometry(m, p);
      const double expected = std::sqrt(m.shot * 255.0 * level + m.read * m.read);
      for (const ImageF* image : {&p.left, &p.right}) {
        const Moments got = moments(*image);
        CAPTURE(bits);
        CAPTURE(level);
        // 65536 draws: sampling error ~0.3 %; 8-bit rounding adds 1/12 grey level^2 (~1 %).
        CHECK(255.0 * got.stddev == doctest::Approx(expected).epsilon(0.05));
        CHECK(std::abs(255.0 * (got.mean - level)) < 0.05 * expected);  // unbiased: 5 % of sigma
      }
    }
}

TEST_CASE("photometry: the noise is reproducible per seed, different across seeds and cameras") {
  CameraPhotometry m = photometryProfile("t265");
  const SynthPair clean = test::smallSynthPair(64, "binocular", 0.12, 3);
  m.seed = 5;
  SynthPair a = clean, b = clean, c = clean;
  applyPhotometry(m, a);
  applyPhotometry(m, b);
  m.seed = 6;
  applyPhotometry(m, c);
  CHECK(a.left.data == b.left.data);
  CHECK(a.right.data == b.right.data);
  CHECK(a.left.data != c.left.data);
  CHECK(a.right.data != c.right.data);
  // Two cameras, two independent streams: identical inputs give different noise.
  SynthPair flat = flatPair(64, 0.3f);
  applyPhotometry(m, flat);
  CHECK(flat.left.data != flat.right.data);
}

TEST_CASE("photometry: output is quantised to the bit depth and the depth is untouched") {
  const SynthPair clean = test::smallSynthPair(64, "binocular", 0.12, 3);
  for (int bits : {8, 16}) {
    CameraPhotometry m = photometryProfile("t265");
    m.bits = bits;
    SynthPair p = clean;
    applyPhotometry(m, p);
    const double levels = bits == 8 ? 255.0 : 65535.0;
    for (float v : p.left.data) {
      REQUIRE(v >= 0.f);
      REQUIRE(v <= 1.f);
      REQUIRE(std::abs(v * levels - std::round(v * levels)) < 1e-3 * (bits == 8 ? 1 : 64));
    }
    CHECK(p.depthLeft.data == clean.depthLeft.data);
    CHECK(p.depthRight.data == clean.depthRight.data);
  }
}

TEST_CASE("photometry: blur is a Gaussian of the given sigma") {
  CameraPhotometry m = bare();
  m.blur = 1.5;
  SynthPair p = flatPair(33, 0.f);
  p.left(16, 16) = 1.f;
  applyPhotometry(m, p);
  double sum = 0.0, second = 0.0;
  for (int y = 0; y < 33; ++y)
    for (int x = 0; x < 33; ++x) sum += p.left(x, y), second += p.left(x, y) * ((x - 16) * (x - 16));
  CHECK(sum == doctest::Approx(1.0).epsilon(1e-3));
  CHECK(std::sqrt(second / sum) == doctest::Approx(1.5).epsilon(0.03));  // truncation at 3 sigma: -1 %
}

TEST_CASE("photometry: bad values are refused with the option's name") {
  auto refused = [](void (*change)(CameraPhotometry&), const char* needle) {
    CameraPhotometry m = photometryProfile("t265");
    change(m);
    CHECK_THROWS_WITH_AS(m.validate(), doctest::Contains(needle), Error);
  };
  refused([](CameraPhotometry& m) { m.left.rim = 0.0; }, "--vignette-left");
  refused([](CameraPhotometry& m) { m.right.rim = 1.5; }, "--vignette-right");
  refused([](CameraPhotometry& m) { m.left.rim = NAN; }, "rim");
  refused([](CameraPhotometry& m) { m.exposure = -0.1; }, "--exposure");
  refused([](CameraPhotometry& m) { m.exposure = NAN; }, "--exposure");
  refused([](CameraPhotometry& m) { m.shot = -1.0; }, "--shot");
  refused([](CameraPhotometry& m) { m.read = -0.5; }, "--read");
  refused([](CameraPhotometry& m) { m.bits = 12; }, "--bits must be 8 or 16");
  refused([](CameraPhotometry& m) { m.gamma = 0.0; }, "--camera-gamma");
  refused([](CameraPhotometry& m) { m.blur = INFINITY; }, "--blur");
  refused([](CameraPhotometry& m) { m.right.gain = 0.0; }, "--gain-right");
  refused([](CameraPhotometry& m) { m.left.offset = 2.0; }, "--offset-left");
  CHECK_THROWS_WITH_AS(parseVignetteMode("cos4"), doctest::Contains("unknown vignette mode 'cos4'"), Error);
  SynthPair black = flatPair(16, 0.f);
  CHECK_THROWS_WITH_AS(applyPhotometry(photometryProfile("t265"), black), doctest::Contains("black image"), Error);
}

TEST_CASE("photometry: a T265-like pair still solves (CPU, preset variational)") {
  SynthPair pair = test::smallSynthPair(160, "binocular", 0.12, 3);
  CameraPhotometry m = photometryProfile("t265");
  m.seed = 3;
  applyPhotometry(m, pair);
  Stereo stereo(pair.rig, preset("variational"), "cpu");
  const DepthResult r = stereo.compute(pair.left, pair.right);
  long long valid = 0, bad = 0;
  for (size_t i = 0; i < r.valid.size(); ++i) {
    if (!r.valid.data[i]) continue;
    ++valid;
    bad += !std::isfinite(r.disparity.data[i]) || !std::isfinite(r.warp.data[i].x) ||
           !std::isfinite(r.warp.data[i].y) || std::isnan(r.depth.radial.data[i]);
  }
  CHECK(valid > 10000);
  CHECK(bad == 0);
  const Metrics metrics = evaluate(pair.rig, r.warp, r.depth.radial, pair.depthLeft, &pair.depthRight);
  MESSAGE("t265 model, 160 px, variational preset: tau>1 " << metrics.tau1 << " %, tau>3 " << metrics.tau3 << " %, EPE "
                                                       << metrics.epe << " px");
  CHECK(metrics.evaluated > 10000);
  // How the bounds were chosen (CPU oracle, this 160 px pair, 2026-11): with the model,
  // seeds 3 / 4 / 5, tau>1 0.9 / 1.2 / 0.7 % and tau>3 0.3 / 0.2 / 0.2 % (clean pairs:
  // tau>1 1.0 / 1.3 / 0.3 %); seed 3 on a data term then in development: 10.6 % / 0.6 %.
  // A warp of zero everywhere (a solve that did nothing) scores tau>1 43 / 48 / 45 %,
  // tau>3 24 / 18 / 22 %. The bounds leave room for data-term changes (this is a sanity
  // check, not an accuracy target) and still fail on a broken solve.
  CHECK(metrics.tau1 < 30.0);
  CHECK(metrics.tau3 < 8.0);
  CHECK(metrics.density > 99.0);
}

TEST_CASE("curvestereo synth / demo: the camera model on the command line") {
  REQUIRE_MESSAGE(fs::exists(cliPath()), "build the curvestereo binary first: " << cliPath());
  const fs::path dir = test::tempDir("photometry_cli");
  const std::string pair = "synth --size 48 --samples 1 --seed 3 --quiet -o ";

  // No camera option: exactly the renderer's images, as before the model existed.
  REQUIRE(runCli(dir, pair + "clean") == 0);
  SynthConfig cfg;
  cfg.camera = defaultFisheye(48);
  cfg.samplesPerAxis = 1;
  cfg.seed = 3;
  const SynthPair rendered = renderPair(cfg);
  writePngGray((dir / "expected_left.png").string(), rendered.left);
  CHECK(readAll(dir / "clean" / "left.png") == readAll(dir / "expected_left.png"));
  CHECK(!fs::exists(dir / "clean" / "photometry.json"));
  REQUIRE(runCli(dir, pair + "none --camera none") == 0);
  CHECK(readAll(dir / "none" / "left.png") == readAll(dir / "clean" / "left.png"));
  CHECK(readAll(dir / "none" / "right.png") == readAll(dir / "clean" / "right.png"));

  // t265: other images, the same ground truth, the parameters beside them.
  std::string out;
  REQUIRE(runCli(dir, pair + "t265 --camera t265 --gain-right 1.1", &out) == 0);
  CHECK(out.find("camera model t265+overrides") != std::string::npos);
  CHECK(readAll(dir / "t265" / "left.png") != readAll(dir / "clean" / "left.png"));
  CHECK(readAll(dir / "t265" / "depth_left.exr") == readAll(dir / "clean" / "depth_left.exr"));
  CHECK(readAll(dir / "t265" / "depth_right.exr") == readAll(dir / "clean" / "depth_right.exr"));
  const std::string json = readAll(dir / "t265" / "photometry.json");
  CHECK(json.find("\"profile\": \"t265+overrides\"") != std::string::npos);
  CHECK(json.find("\"right\": {\"rim\": 0.35, \"gain\": 1.1, \"offset\": 0}") != std::string::npos);
  CHECK(json.find("\"seed\": 3") != std::string::npos);  // the scene seed unless --noise-seed

  // 16 bits on request.
  REQUIRE(runCli(dir, pair + "deep --camera t265 --bits 16 --noise-seed 9") == 0);
  PngFormat format;
  readPngGray((dir / "deep" / "left.png").string(), &format);
  CHECK(format.bitDepth == 16);
  CHECK(readAll(dir / "deep" / "photometry.json").find("\"seed\": 9") != std::string::npos);

  // The demo renders through the same model and says so.
  REQUIRE(runCli(dir, "demo --size 48 --backend cpu --preset realtime --levels 2 --camera t265 -o demo", &out) == 0);
  CHECK(out.find("camera model t265") != std::string::npos);
  CHECK(fs::exists(dir / "demo" / "photometry.json"));
  CHECK(fs::exists(dir / "demo" / "depth.exr"));
}

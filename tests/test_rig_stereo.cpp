// RigStereo's concurrency and the reusable panorama fusion (issue 32): a rig's pair directions
// solve on threads of their own, one Stereo each, which must change no bit of any result on
// any backend here; PanoramaFusion computes the cameras' rays once and must fuse as
// fusePanorama does, on the CPU bit for bit and on the GPU backends to rounding.
#include <cstring>
#include <limits>
#include <memory>

#include "curvestereo/backends.hpp"
#include "curvestereo/rig_fusion.hpp"
#include "curvestereo/rig_stereo.hpp"
#include "synth/rig.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

// ring4 (four 180-degree fisheyes) small enough for every backend here, lavapipe included.
const synth::SynthRig& ring4() {
  static const synth::SynthRig rig = [] {
    synth::RigConfig cfg;
    cfg.size = 64;
    cfg.samplesPerAxis = 1;
    cfg.panoramaWidth = 128;
    return synth::renderRig(cfg);
  }();
  return rig;
}

Params shortSolve(const CameraRig& rig) {
  Params params = rigParams(rig, preset("fast"));
  params.warps = test::shortUnderSanitizers(params.warps);
  return params;
}

bool sameResult(const DepthResult& a, const DepthResult& b) {
  return a.valid.data == b.valid.data && test::sameBits(a.depth.radial, b.depth.radial) &&
         test::sameBits(a.confidence, b.confidence) && test::sameBits(a.disparity, b.disparity);
}

// ring4 solved once on the CPU with every pair, for the panorama's tests.
struct SolvedRing {
  std::unique_ptr<RigStereo> stereo;
  RigResult result;
  PanoramaFrame frame;
};
const SolvedRing& solvedRing() {
  static const SolvedRing solved = [] {
    const CameraRig& rig = ring4().layout.rig;
    SolvedRing s{std::make_unique<RigStereo>(rig, choosePairs(rig), shortSolve(rig), "cpu"), {}, panoramaFrame(rig)};
    s.result = s.stereo->compute(ring4().images);
    return s;
  }();
  return solved;
}

std::vector<std::string> backendsHere() {
  std::vector<std::string> usable;
  for (const std::string& name : availableBackends())
    if (backendAvailable(name)) usable.push_back(name);
  return usable;
}

}  // namespace

TEST_CASE("a rig's directions solved concurrently equal one after the other, bit for bit, on every backend") {
  const synth::SynthRig& synthetic = ring4();
  const CameraRig& rig = synthetic.layout.rig;
  // One partner each: two pairs, four directions on four threads (a Vulkan Stereo takes a
  // second to set up on lavapipe, so one object serves both ways: a frame does not depend
  // on the frames before it).
  const std::vector<PairInfo> pairs = choosePairs(rig, 1);
  for (const std::string& backend : backendsHere()) {
    CAPTURE(backend);
    RigStereo stereo(rig, pairs, shortSolve(rig), backend);
    stereo.setConcurrentSolves(false);
    const RigResult one = stereo.compute(synthetic.images);
    stereo.setConcurrentSolves(true);
    const RigResult all = stereo.compute(synthetic.images);
    REQUIRE(one.cameras.size() == 4);
    REQUIRE(all.cameras.size() == 4);
    CHECK(all.solves.size() == 2 * pairs.size());
    for (size_t k = 0; k < 4; ++k) {
      CAPTURE(k);
      CHECK(sameResult(one.cameras[k], all.cameras[k]));
    }
  }
}

TEST_CASE("each direction solves the window its partner sees, with the whole image's result") {
  const synth::SynthRig& synthetic = ring4();
  const CameraRig& rig = synthetic.layout.rig;
  const std::vector<PairInfo> pairs = choosePairs(rig);
  RigStereo stereo(rig, pairs, shortSolve(rig), "cpu");
  const RigResult windowed = stereo.compute(synthetic.images);
  // Without points the fusion leaves z and points out, and changes nothing else.
  stereo.setPointOutputs(false);
  const RigResult depthOnly = stereo.compute(synthetic.images);
  for (size_t k = 0; k < 4; ++k) {
    CHECK(depthOnly.cameras[k].depth.points.empty());
    CHECK(depthOnly.cameras[k].depth.z.empty());
    CHECK(sameResult(depthOnly.cameras[k], windowed.cameras[k]));
    CHECK(windowed.cameras[k].depth.points.width == 64);
  }
  CHECK(windowed.fusionMs > 0);
  CHECK(windowed.fusionMs < windowed.totalMs);
  stereo.setPointOutputs(true);
  stereo.setSolveWindows(false);
  const RigResult whole = stereo.compute(synthetic.images);
  REQUIRE(windowed.solves.size() == 2 * pairs.size());
  for (size_t d = 0; d < windowed.solves.size(); ++d) {
    const ImageWindow& w = windowed.solves[d].window;
    CAPTURE(d);
    CHECK(w.width < 0.8 * 64);  // about half the image, and the margin
    CHECK(w.height == 64);
    CHECK(whole.solves[d].window.width == 64);
  }
  for (size_t k = 0; k < 4; ++k) {
    CAPTURE(k);
    const DepthResult &a = windowed.cameras[k], &b = whole.cameras[k];
    long long both = 0, agree = 0, onlyOne = 0;
    for (size_t i = 0; i < a.valid.size(); ++i) {
      onlyOne += a.valid.data[i] != b.valid.data[i];
      if (!a.valid.data[i] || !b.valid.data[i]) continue;
      ++both;
      const double ia = 1.0 / a.depth.radial.data[i], ib = 1.0 / b.depth.radial.data[i];
      agree += std::abs(ia - ib) <= 0.05 * std::max(ia, ib) + 1e-3;
    }
    MESSAGE("cam" << k << ": " << both << " px in both, " << agree << " agree, " << onlyOne << " in one");
    CHECK(both > 1000);
    CHECK(double(onlyOne) <= 0.02 * double(both));
    CHECK(double(agree) >= 0.9 * double(both));
  }
}

// The GPU backends sum in their atomics' order, and their atan2 and cos may differ by ulps,
// which may move a footprint's edge across a pixel where it lies within 1e-4 px of one: the
// same panorama to rounding but for those few pixels, on the second frame as on the first
// (the resolve left the accumulator clean).
TEST_CASE("the panorama on every backend here equals the CPU's to rounding, frame after frame") {
  const synth::SynthRig& synthetic = ring4();
  const auto& [stereoPtr, r, frame] = solvedRing();
  const CameraRig& rig = synthetic.layout.rig;
  const RigStereo& stereo = *stereoPtr;
  const Panorama cpu = fusePanorama(rig, r.cameras, synthetic.images, frame, 128);
  for (const std::string& backend : backendsHere()) {
    CAPTURE(backend);
    PanoramaFusion fusion(rig, frame, 128, stereo.rays(), backend);
    CHECK(fusion.backendName() == backend);
    for (int frameIndex = 0; frameIndex < 2; ++frameIndex) {
      const Panorama p = fusion.fuse(r.cameras, synthetic.images);
      long long differentState = 0, far = 0, ranged = 0;
      for (size_t i = 0; i < cpu.range.data.size(); ++i) {
        const float a = p.range.data[i], b = cpu.range.data[i];
        if (std::isnan(a) != std::isnan(b) || std::isinf(a) != std::isinf(b)) ++differentState;
        if (!std::isfinite(a) || !std::isfinite(b)) continue;
        ++ranged;
        far += std::abs(a - b) > 1e-4f * b || std::abs(p.confidence.data[i] - cpu.confidence.data[i]) > 1e-6f ||
               std::abs(p.grey.data[i] - cpu.grey.data[i]) > 1e-5f;
      }
      MESSAGE(backend << " frame " << frameIndex << ": " << differentState << " px of another state, " << far
                      << " px beyond rounding, of " << ranged);
      CHECK(ranged > cpu.range.size() / 2);
      CHECK(differentState * 1000 <= ranged);
      CHECK(far * 500 <= ranged);
    }
  }
}

TEST_CASE("a direction's error reaches the caller once every solve has ended, and the rig solves again after") {
  const synth::SynthRig& synthetic = ring4();
  const CameraRig& rig = synthetic.layout.rig;
  RigStereo stereo(rig, choosePairs(rig), shortSolve(rig), "cpu");
  std::vector<ImageF> images = synthetic.images;
  images[2] = ImageF(32, 32, 0.5f);  // camera 2 is 64 px: refused before any solve, by camera
  CHECK(test::errorOf([&] { stereo.compute(images); }) == "cam2's image is 32x32 but the camera is 64x64");
  // An error inside one direction's solve (here a NaN pixel, which every solve refuses)
  // reaches the caller once every direction has ended.
  images[2] = synthetic.images[2];
  images[1].data[0] = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_AS(stereo.compute(images), Error);
  const RigResult r = stereo.compute(synthetic.images);
  for (const DepthResult& cam : r.cameras) {
    long long valid = 0;
    for (uint8_t v : cam.valid.data) valid += v;
    CHECK(valid > cam.valid.size() / 3);  // a depth over the overlaps
  }
}

TEST_CASE("PanoramaFusion reused over frames, or from RigStereo's rays, fuses as fusePanorama, bit for bit") {
  const synth::SynthRig& synthetic = ring4();
  const auto& [stereoPtr, r, frame] = solvedRing();
  const CameraRig& rig = synthetic.layout.rig;
  const RigStereo& stereo = *stereoPtr;
  PanoramaFusion fusion(rig, frame, 128), fromStereosRays(rig, frame, 128, stereo.rays());
  for (float minConfidence : {0.f, 0.3f}) {
    CAPTURE(minConfidence);
    const Panorama once = fusePanorama(rig, r.cameras, synthetic.images, frame, 128, minConfidence);
    Panorama again;  // reused: the second frame writes over the first
    for (int frameIndex = 0; frameIndex < 2; ++frameIndex) {
      for (PanoramaFusion* f : {&fusion, &fromStereosRays}) {
        f->fuse(r.cameras, synthetic.images, again, minConfidence);
        CHECK(test::sameBits(again.range, once.range));
        CHECK(test::sameBits(again.grey, once.grey));
        CHECK(test::sameBits(again.confidence, once.confidence));
      }
    }
    long long ranged = 0;
    for (float v : once.range.data) ranged += !std::isnan(v);
    CHECK(ranged > once.range.size() / 2);  // the fusion did something to compare
  }
  CHECK_THROWS_WITH_AS(PanoramaFusion(rig, frame, 127), "panorama width must be even and 4 to 32768 px, got 127",
                       Error);
  std::string available;
  for (const std::string& n : availableBackends()) available += (available.empty() ? "" : ", ") + n;
  CHECK(test::errorOf([&] { PanoramaFusion(rig, frame, 128, "nonesuch"); }) ==
        "backend 'nonesuch' is not available in this build (available: " + available + ", auto)");
  CHECK_THROWS_AS(fusion.fuse({r.cameras[0]}, {}), Error);
  const std::vector<CameraRays> tooFew(stereo.rays().begin(), stereo.rays().end() - 1);
  CHECK_THROWS_WITH_AS(PanoramaFusion(rig, frame, 128, tooFew),
                       "PanoramaFusion: the rays given are not one per camera, each its camera's size", Error);
}

TEST_CASE(
    "one way: each pair solved once, every camera of a ring solving once, and the views' panorama covers as much") {
  const synth::SynthRig& synthetic = ring4();
  const CameraRig& rig = synthetic.layout.rig;
  const std::vector<PairInfo> pairs = choosePairs(rig);
  const auto& [bothWays, both, frame] = solvedRing();
  RigStereo oneWay(rig, pairs, shortSolve(rig), "cpu");
  oneWay.setOneWay(true);
  const std::vector<PanoramaView> views = oneWay.views();
  REQUIRE(views.size() == pairs.size());
  std::vector<int> solvesFrom(size_t(rig.size()), 0);
  for (const PanoramaView& v : views) ++solvesFrom[size_t(v.camera)];
  for (int n : solvesFrom) CHECK(n == 1);  // a ring of four, four pairs: one each
  const RigResult r = oneWay.compute(synthetic.images);
  REQUIRE(r.views.size() == views.size());
  REQUIRE(r.solves.size() == views.size());
  for (size_t d = 0; d < views.size(); ++d) {
    CHECK(r.solves[d].reference == views[d].camera);
    CHECK(r.views[d].valid.width == views[d].window.width);
  }
  // Both ways, the views' panorama is the cameras' (a camera pixel's estimates fused first or
  // in the panorama); one way, it covers the sphere about as well from half the solves.
  const auto covered = [](const Panorama& p) {
    long long n = 0;
    for (float v : p.range.data) n += !std::isnan(v);
    return double(n) / double(p.range.size());
  };
  const Panorama fromCameras = fusePanorama(rig, both.cameras, synthetic.images, frame, 128);
  const Panorama fromViews =
      PanoramaFusion(rig, frame, 128, bothWays->views(), bothWays->rays()).fuse(both.views, synthetic.images);
  const Panorama oneWayViews = PanoramaFusion(rig, frame, 128, views, oneWay.rays()).fuse(r.views, synthetic.images);
  CHECK(covered(fromViews) == doctest::Approx(covered(fromCameras)).epsilon(0.01));
  CHECK(covered(oneWayViews) > 0.95 * covered(fromCameras));
  // Against the rendered truth: one estimate a point rather than two costs some accuracy, not
  // the surface (the mean relative range error, capped at 1, as eval's abs-rel).
  const auto absRel = [&](const Panorama& p) {
    double sum = 0;
    long long n = 0;
    for (size_t i = 0; i < p.range.data.size(); ++i) {
      const float gt = synthetic.panoramaRange.data[i], est = p.range.data[i];
      if (!std::isfinite(gt) || !(gt > 0) || std::isnan(est)) continue;
      sum += std::isfinite(est) ? std::min(1.0, std::abs(double(est) - gt) / gt) : 1.0, ++n;
    }
    return sum / double(std::max(1LL, n));
  };
  MESSAGE("abs-rel: both ways " << absRel(fromViews) << ", one way " << absRel(oneWayViews));
  CHECK(absRel(oneWayViews) < 1.5 * absRel(fromViews) + 0.01);
  // Each camera's own window, and beyond it its partner's estimate carried into it.
  for (int k = 0; k < rig.size(); ++k) {
    long long one = 0, two = 0;
    for (uint8_t v : r.cameras[size_t(k)].valid.data) one += v;
    for (uint8_t v : both.cameras[size_t(k)].valid.data) two += v;
    CHECK(one > 0.85 * double(two));
  }
  // The cross-check needs both directions: one way refuses it, in either order.
  const std::string refused = "the cross-check compares a pair's two directions: one way (--one-way) solves only one";
  CHECK(test::errorOf([&] { oneWay.setCrossCheck(0.1); }) == refused);
  RigStereo checked(rig, pairs, shortSolve(rig), "cpu");
  checked.setCrossCheck(0.1);
  CHECK(test::errorOf([&] { checked.setOneWay(true); }) == refused);
  // Without camera outputs, only the views come back.
  oneWay.setCameraOutputs(false);
  CHECK(oneWay.compute(synthetic.images).cameras.empty());
}

TEST_CASE("RigStereo's own panorama, each view placed as its solve ends, is PanoramaFusion's over the views") {
  const synth::SynthRig& synthetic = ring4();
  const CameraRig& rig = synthetic.layout.rig;
  const PanoramaFrame frame = panoramaFrame(rig);
  for (double crossCheck : {0.0, 0.1}) {
    CAPTURE(crossCheck);
    RigStereo stereo(rig, choosePairs(rig), shortSolve(rig), "cpu");
    stereo.setCrossCheck(crossCheck);
    stereo.setPanorama(128, frame, 0.1f);
    RigResult r;
    for (int frameIndex = 0; frameIndex < 2; ++frameIndex) {  // the fusion's state reused
      stereo.compute(synthetic.images, r);
      const Panorama expected =
          PanoramaFusion(rig, frame, 128, stereo.views(), stereo.rays()).fuse(r.views, synthetic.images, 0.1f);
      CHECK(test::sameBits(r.panorama.range, expected.range));
      CHECK(test::sameBits(r.panorama.confidence, expected.confidence));
      CHECK(test::sameBits(r.panorama.grey, expected.grey));
      CHECK(r.panoramaMs > 0);
    }
  }
  RigStereo stereo(rig, choosePairs(rig), shortSolve(rig), "cpu");
  CHECK(stereo.compute(synthetic.images).panorama.range.empty());  // none unless asked for
  CHECK(test::errorOf([&] { stereo.setPanorama(127, frame); }) ==
        "panorama width must be even and 4 to 32768 px, got 127");
}

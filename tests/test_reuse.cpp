// Stereo::compute(left, right, result): the reuse overload a real-time loop calls every
// frame. It gives results bit-identical to compute(left, right) by value, whatever
// `result` held before (other frames, wrong sizes, outputs since dropped), keeps the
// storage of images whose size matches, and derives the valid mask from the radial depth.
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "curvestereo/backend.hpp"
#include "curvestereo/stereo.hpp"
#include "synth/scene.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

synth::SynthPair render(const std::string& motion, uint32_t seed) {
  return test::smallSynthPair(64, motion, 0.15, seed);
}

// Two solver configurations: without and with the plane-sweep initialiser (confidence).
std::vector<std::pair<std::string, Params>> configurations() {
  Params fast = preset("variational");
  fast.warps = 3;
  Params sweep = preset("quality");
  sweep.warps = 3;
  return {{"no initialiser", fast}, {"quality", sweep}};
}

// A Stereo on `backend`, or null (reported) when that backend cannot run here.
std::unique_ptr<Stereo> tryStereo(const Rig& rig, const Params& params, const std::string& backend) {
  try {
    return std::make_unique<Stereo>(rig, params, backend);
  } catch (const Error& e) {
    MESSAGE("SKIPPED backend " << backend << ": " << std::string(e.what()));
    return nullptr;
  }
}

template <class T>
bool sameBits(const Image<T>& a, const Image<T>& b) {
  return a.width == b.width && a.height == b.height && a.data.size() == b.data.size() &&
         (a.data.empty() || std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(T)) == 0);
}

void checkSame(const DepthResult& got, const DepthResult& want) {
  CHECK(sameBits(got.valid, want.valid));
  CHECK(sameBits(got.disparity, want.disparity));
  CHECK(sameBits(got.warp, want.warp));
  CHECK(sameBits(got.depth.radial, want.depth.radial));
  CHECK(sameBits(got.depth.z, want.depth.z));
  CHECK(sameBits(got.depth.points, want.depth.points));
  CHECK(sameBits(got.confidence, want.confidence));
  CHECK(got.stages.size() == want.stages.size());
}

// Images of the wrong size in every field, and stale stages.
DepthResult wrongSized() {
  DepthResult r;
  r.valid = ImageU8(10, 10, 1);
  r.disparity = ImageF(1, 1, 3.f);
  r.depth.radial = ImageF(200, 3, 7.f);
  r.depth.z = ImageF(5, 5);
  r.depth.points = Image<Point3f>(70, 70);
  r.confidence = ImageF(3, 3, 0.5f);
  r.stages = {{"stale", 1.0}};
  r.totalMs = -1;
  return r;
}

}  // namespace

TEST_CASE("compute into a DepthResult: bit-identical to compute by value, frame after frame, on every backend") {
  const synth::SynthPair a = render("binocular", 21), b = render("binocular", 22);
  for (const auto& [configName, params] : configurations()) {
    for (const std::string& backend : availableBackends()) {
      INFO("backend " << backend << ", " << configName);
      // Same sequence on two objects: one returns new results, one writes into `reused`.
      auto byValue = tryStereo(a.rig, params, backend);
      auto into = tryStereo(a.rig, params, backend);
      if (!byValue || !into) continue;

      {  // two frames with different inputs into the same result
        DepthResult reused;
        for (const synth::SynthPair* p : {&a, &b}) {
          const DepthResult want = byValue->compute(p->left, p->right);
          into->compute(p->left, p->right, reused);
          checkSame(reused, want);
          CHECK(reused.totalMs >= 0);
        }
      }
      {  // a result that starts with images of the wrong size
        DepthResult reused = wrongSized();
        const DepthResult want = byValue->compute(a.left, a.right);
        into->compute(a.left, a.right, reused);
        checkSame(reused, want);
        CHECK(reused.stages.empty());
        CHECK(reused.totalMs >= 0);
        CHECK(!reused.confidence.empty());  // every preset has a confidence
      }
      // The rest is the same with the initialiser, which costs most of a second per frame
      // on lavapipe: once is enough.
      if (params.init != Params::Init::None) continue;
      {  // outputs dropped between frames come back empty, and return when selected again
        DepthResult reused;
        (void)byValue->compute(a.left, a.right);  // both objects see the same frames
        into->compute(a.left, a.right, reused);
        for (const Stereo::Outputs& outputs :
             {Stereo::Outputs{false, true, false}, Stereo::Outputs{false, false, false},
              Stereo::Outputs{true, false, true}, Stereo::Outputs{true, true, true}}) {
          CAPTURE(outputs.disparity);
          CAPTURE(outputs.warp);
          CAPTURE(outputs.points);
          byValue->setOutputs(outputs);
          into->setOutputs(outputs);
          const DepthResult want = byValue->compute(b.left, b.right);
          into->compute(b.left, b.right, reused);
          checkSame(reused, want);
          CHECK(reused.disparity.empty() == !outputs.disparity);
          CHECK(reused.warp.empty() == !outputs.warp);
          CHECK(reused.depth.points.empty() == !outputs.points);
          CHECK(reused.depth.z.empty() == !outputs.points);
          CHECK(!reused.valid.empty());
          CHECK(!reused.depth.radial.empty());
        }
      }
      {  // with profiling: the stages of this frame only
        byValue->setProfiling(true);
        into->setProfiling(true);
        DepthResult reused = wrongSized();
        for (int frame = 0; frame < 2; ++frame) {
          const DepthResult want = byValue->compute(b.left, b.right);
          into->compute(b.left, b.right, reused);
          checkSame(reused, want);
          REQUIRE(!reused.stages.empty());
          CHECK(reused.stages.front().name != "stale");
        }
      }
    }
  }
}

TEST_CASE("compute into a DepthResult keeps the storage of its images") {
  const synth::SynthPair a = render("binocular", 21), b = render("forward", 23);
  for (const auto& [configName, params] : configurations()) {
    for (const std::string& backend : availableBackends()) {
      INFO("backend " << backend << ", " << configName);
      auto stereo = tryStereo(a.rig, params, backend);
      if (!stereo) continue;
      DepthResult r;
      stereo->compute(a.left, a.right, r);
      const void* valid = r.valid.data.data();
      const void* radial = r.depth.radial.data.data();
      const void* z = r.depth.z.data.data();
      const void* disparity = r.disparity.data.data();
      const void* warp = r.warp.data.data();
      const void* points = r.depth.points.data.data();
      const void* confidence = r.confidence.data.data();
      stereo->compute(b.left, b.right, r);
      CHECK(r.valid.data.data() == valid);
      CHECK(r.depth.radial.data.data() == radial);
      CHECK(r.depth.z.data.data() == z);
      CHECK(r.disparity.data.data() == disparity);
      CHECK(r.warp.data.data() == warp);
      CHECK(r.depth.points.data.data() == points);
      CHECK(r.confidence.data.data() == confidence);
    }
  }
}

TEST_CASE("the valid mask is exactly where the radial depth is not NaN") {
  // Forward motion masks the epipoles as well as the rim: invalid pixels inside the image.
  for (const std::string motion : {"binocular", "forward"}) {
    const synth::SynthPair pair = render(motion, 24);
    for (const std::string& backend : availableBackends()) {
      INFO("backend " << backend << ", " << motion);
      auto stereo = tryStereo(pair.rig, configurations().front().second, backend);
      if (!stereo) continue;
      for (const bool allOutputs : {true, false}) {
        stereo->setOutputs({allOutputs, allOutputs, allOutputs});
        const DepthResult r = stereo->compute(pair.left, pair.right);
        REQUIRE(r.valid.size() == r.depth.radial.size());
        long long valid = 0, mismatched = 0;
        for (size_t i = 0; i < r.valid.size(); ++i) {
          valid += r.valid.data[i];
          mismatched += (r.valid.data[i] == 1) != !std::isnan(r.depth.radial.data[i]);
          mismatched += r.valid.data[i] > 1;
        }
        CHECK(mismatched == 0);
        CHECK(valid > 0);
        CHECK(valid < (long long)r.valid.size());  // the rim outside the image circle is invalid
      }
    }
  }
}

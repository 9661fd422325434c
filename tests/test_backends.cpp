// Every kernel on every backend present at run time, against the CPU oracle, with an
// explicit error metric per kernel (in the manner of ggml's test-backend-ops); then whole
// solves end to end; the coarse kernels against their fine sequences on the same backend;
// progress on replayed frames. A backend that is absent or unusable is reported as
// skipped, and the suite to ctest as skipped when no backend besides the CPU ran
// (gpu_suite.hpp).
#include <cmath>

#include "curvestereo/metrics.hpp"
#include "curvestereo/stereo.hpp"
#include "forwarding_backend.hpp"
#include "golden_cases.hpp"
#include "gpu_suite.hpp"
#include "synth/scene.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

struct Tolerance {
  double maxAbs, nmse;
};

// Float kernels on GPUs differ from the oracle by rounding (fused multiply-adds,
// reordered sums, device exp/pow): a few ulps of values of order 1.
Tolerance toleranceFor(const std::string& output) {
  if (output.rfind("fields_", 0) == 0) return {2e-3, 1e-9};       // float camera models vs double
  if (output.rfind("triangulate_", 0) == 0) return {1e-2, 1e-8};  // metres; far points amplify rounding
  if (output.rfind("tensor_", 0) == 0) return {2e-4, 1e-9};
  // The oracle's order of summation, no contraction: bit-exact on lavapipe (and CUDA with
  // IEEE division and square root). Vulkan allows 2.5-ulp division and square root: on the
  // case's values (|output| <= 2.2, local spread down to epsilon) that moves the output by
  // <= 1.7e-5 (the oracle re-run with each quotient and root off by 2.5 ulp, every sign).
  if (output.rfind("normalise_", 0) == 0) return {1e-4, 1e-9};
  // Sweep geometry like the fields (float camera models vs double): a hypothesis lands up
  // to ~2e-3 px away. The volume is the golden texture sampled there (steps <= 0.13 per
  // px, so <= 2.6e-4); w and u are those positions; the confidence's slope in e is at most
  // sqrt(2/e) / tol = 0.57 per px at the case's tol = 1.5 px.
  if (output.rfind("sweepwarp_", 0) == 0) return {5e-4, 1e-9};
  if (output.rfind("sweepinit_", 0) == 0) return {2e-3, 1e-8};
  // 1 - ZNCC from one-pass float sums: the oracle's own cost is ~4e-5 from the exact one
  // (measured: float vs double sums on the case), a backend summing in another order is
  // as far again.
  if (output.rfind("sweepcost_", 0) == 0) return {2e-4, 1e-9};
  // Aggregation is minima and float adds in a fixed order: exact on every backend; the
  // bound only allows for printing. Selection: exact inputs, one float division in the
  // parabola and q in double (float on Vulkan devices without float64): ~1e-6 of q.
  if (output.rfind("sweepaggregate_", 0) == 0) return {1e-6, 1e-15};
  if (output.rfind("sweepselect_", 0) == 0) return {1e-5, 1e-12};
  // The band sweep's kernels: the same reasons. Its first hypotheses are integers from a
  // case whose proposals lie 0.2 plane from a rounding tie: exact.
  if (output == "sweepbandwarp_first") return {0.0, 0.0};
  if (output.rfind("sweepbandwarp_", 0) == 0) return {5e-4, 1e-9};
  // At radius 1 a window holds 5 to 9 samples: smaller variances, so Vulkan's 2.5-ulp
  // division and square root move 1 - ZNCC further (2.8e-4 measured on NVIDIA's driver at
  // one pixel, NMSE 1.7e-11; CUDA and lavapipe exact).
  if (output == "sweepbandcost_radius1") return {5e-4, 1e-9};
  if (output.rfind("sweepbandcost_", 0) == 0) return {2e-4, 1e-9};
  if (output.rfind("sweepbandaggregate_", 0) == 0) return {1e-6, 1e-15};
  if (output.rfind("sweepbandselect_", 0) == 0) return {1e-5, 1e-12};
  // Carried states: double geometry on every backend, one nearest-pixel lookup per step
  // (a lookup would only change at a rounding tie), q in double rounded to float once.
  if (output.rfind("carry_", 0) == 0) return {1e-5, 1e-12};
  // The round trip: three bilinear samples, float adds and a square root of errors of a few
  // px; Vulkan may fuse the samples' multiply-adds and rounds sqrt to 2.5 ulp (1.7e-5 px
  // measured on lavapipe, a few ulps of 4). The confidence: window sums in the oracle's
  // order and the device's exp (a few ulps of a value <= 1).
  if (output.rfind("roundtrip_", 0) == 0) return {5e-5, 1e-10};
  if (output.rfind("confidence_", 0) == 0) return {1e-5, 1e-12};
  return {1e-4, 1e-9};
}

std::vector<std::string> otherBackends() {
  std::vector<std::string> names;
  for (const std::string& n : availableBackends())
    if (n != "cpu") names.push_back(n);
  return names;
}

// The backend, or null (with the reason reported) when it cannot run here.
std::unique_ptr<Backend> tryBackend(const std::string& name) {
  try {
    auto backend = createBackend(name);
    test::gpuUsed();
    return backend;
  } catch (const Error& e) {
    MESSAGE("SKIPPED backend " << name << ": " << std::string(e.what()));
    return nullptr;
  }
}

// Forwards every fine kernel to a backend but keeps Backend's default coarse kernels: the
// coarse kernels' documented sequences of fine kernels, run on that backend.
class FineKernelsOf final : public test::ForwardingBackend {
 public:
  using ForwardingBackend::ForwardingBackend;
};

bool coarseKernel(const std::string& kernel) {
  return kernel.rfind("warpIterations", 0) == 0 || kernel.rfind("warpTail", 0) == 0;
}

}  // namespace

TEST_CASE("every kernel on every backend matches the CPU oracle") {
  if (otherBackends().empty()) MESSAGE("SKIPPED: no backend besides cpu is compiled into this build");
  auto cpu = createBackend("cpu");
  for (const std::string& name : otherBackends()) {
    auto backend = tryBackend(name);
    if (!backend) continue;
    for (const auto& c : golden::kernelCases()) {
      const auto expected = c.run(*cpu);
      const auto actual = c.run(*backend);
      REQUIRE(actual.size() == expected.size());
      for (size_t i = 0; i < actual.size(); ++i) {
        INFO("backend " << name << ", kernel " << c.kernel << ", output " << actual[i].name);
        const Tolerance tol = toleranceFor(actual[i].name);
        golden::Difference d = golden::compare(actual[i].planes, expected[i].planes, tol.maxAbs);
        MESSAGE(name << " " << actual[i].name << ": max abs " << d.maxAbs << ", NMSE " << d.nmse);
        CHECK(d.mismatchedNonFinite == 0);
        CHECK(d.maxAbs <= tol.maxAbs);
        CHECK(d.nmse <= tol.nmse);
      }
    }
  }
}

TEST_CASE("whole solves on every backend agree with the CPU oracle") {
  if (otherBackends().empty()) {
    MESSAGE("SKIPPED: no backend besides cpu is compiled into this build");
    return;
  }
  synth::SynthConfig cfg;
  cfg.camera = synth::defaultFisheye(161);
  cfg.baseline = 0.12;
  cfg.seed = 9;
  cfg.samplesPerAxis = 2;
  const synth::SynthPair pair = synth::renderPair(cfg);
  // "quality" adds the plane-sweep initialiser (its winner-take-all choice and left-right
  // check are discrete, so this also shows backends rarely flip them).
  for (const char* presetName : {"variational", "quality"}) {
    Params params = preset(presetName);
    params.minWidth = 20;
    params.warps = 12;
    Stereo oracle(pair.rig, params, "cpu");
    const DepthResult ref = oracle.compute(pair.left, pair.right);
    const Metrics refMetrics = evaluate(pair.rig, ref.warp, ref.depth.radial, pair.depthLeft, &pair.depthRight);
    for (const std::string& name : otherBackends()) {
      if (!tryBackend(name)) continue;
      Stereo stereo(pair.rig, params, name);
      // Twice: the second frame may be a replay of a recorded one.
      for (int frame = 0; frame < 2; ++frame) {
        const DepthResult r = stereo.compute(pair.left, pair.right);
        INFO("backend " << name << ", preset " << std::string(presetName) << ", frame " << frame);
        CHECK(r.valid.data == ref.valid.data);
        CHECK(r.confidence.empty() == ref.confidence.empty());
        long long valid = 0, close = 0, closeConfidence = 0;
        for (size_t i = 0; i < r.valid.size(); ++i) {
          if (!ref.valid.data[i]) continue;
          ++valid;
          close += std::abs(r.disparity.data[i] - ref.disparity.data[i]) <= 0.05f;
          if (!ref.confidence.empty() && !r.confidence.empty())
            closeConfidence += std::abs(r.confidence.data[i] - ref.confidence.data[i]) <= 0.05f;
        }
        const Metrics m = evaluate(pair.rig, r.warp, r.depth.radial, pair.depthLeft, &pair.depthRight);
        MESSAGE(name << " " << std::string(presetName) << " frame " << frame << ": " << 100.0 * close / valid
                     << " % within 0.05 px; tau>1 " << m.tau1 << " vs " << refMetrics.tau1 << ", tau>3 " << m.tau3
                     << " vs " << refMetrics.tau3);
        CHECK(double(close) >= 0.99 * double(valid));
        if (!ref.confidence.empty()) CHECK(double(closeConfidence) >= 0.99 * double(valid));
        CHECK(std::abs(m.tau1 - refMetrics.tau1) <= 0.2);
        CHECK(std::abs(m.tau3 - refMetrics.tau3) <= 0.2);
      }
    }
  }
}

// A backend may fuse a coarse kernel's sequence (CUDA does), but must give its results: bit
// for bit the fine kernels' on the same backend.
TEST_CASE("every coarse kernel on every backend gives its fine kernels' results on that backend") {
  std::vector<std::string> names = otherBackends();
  names.insert(names.begin(), "cpu");
  for (const std::string& name : names) {
    auto backend = name == "cpu" ? createBackend("cpu") : tryBackend(name);
    if (!backend) continue;
    FineKernelsOf fine(*backend);
    for (const auto& c : golden::kernelCases()) {
      if (!coarseKernel(c.kernel)) continue;
      const auto coarse = c.run(*backend), sequence = c.run(fine);
      REQUIRE(coarse.size() == sequence.size());
      for (size_t i = 0; i < coarse.size(); ++i) {
        INFO("backend " << name << ", kernel " << c.kernel << ", output " << coarse[i].name);
        long long differ = 0;
        for (size_t k = 0; k < coarse[i].planes.data.size(); ++k) {
          const float a = coarse[i].planes.data[k], b = sequence[i].planes.data[k];
          differ += !(a == b || (std::isnan(a) && std::isnan(b)));
        }
        CHECK(differ == 0);
      }
    }
  }
}

// stereo.hpp: a frame issued warp by warp reports after every warp, ending at 1; a frame a
// GPU backend replays reports exactly 0 and 1 (nothing runs on the host in between).
TEST_CASE("progress: every warp of an issued frame, 0 and 1 of a replayed one") {
  const synth::SynthPair pair = test::smallSynthPair(61, "binocular", 0.12, 4);
  Params params = preset("variational");
  params.minWidth = 20;
  params.warps = 3;
  params.init = Params::Init::None;  // one report per warp, no sweep step
  const size_t warps = pyramidPlan(pair.left.width, pair.left.height, params).size() * size_t(params.warps);
  REQUIRE(warps > 2);
  std::vector<std::string> names = otherBackends();
  names.insert(names.begin(), "cpu");
  for (const std::string& name : names) {
    if (name != "cpu" && !tryBackend(name)) continue;
    Stereo stereo(pair.rig, params, name);
    std::vector<double> calls;
    stereo.setProgress([&](double f) { calls.push_back(f); });
    for (int frame = 0; frame < 4; ++frame) {  // CUDA replays from the third, Vulkan from the second
      INFO("backend " << name << ", frame " << frame);
      calls.clear();
      stereo.compute(pair.left, pair.right);
      const bool replayed = calls.size() == 2;
      if (name == "cpu") CHECK_FALSE(replayed);          // the CPU never replays
      if (name != "cpu" && frame == 3) CHECK(replayed);  // a GPU backend does by the fourth frame
      if (replayed) {
        CHECK(calls == std::vector<double>{0.0, 1.0});
        continue;
      }
      REQUIRE(calls.size() == warps);
      CHECK(calls.back() == 1.0);
      for (size_t i = 0; i < calls.size(); ++i) {
        CHECK(calls[i] > 0.0);
        if (i > 0) CHECK(calls[i] > calls[i - 1]);
      }
    }
  }
}

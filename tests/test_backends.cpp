// Every kernel on every backend present at run time, against the CPU oracle, with an
// explicit error metric per kernel output, which the case states with its reason (in the
// manner of ggml's test-backend-ops); then whole
// solves end to end; the coarse kernels against their fine sequences on the same backend;
// progress on replayed frames. A backend that is absent or unusable is reported as
// skipped, and the suite to ctest as skipped when no backend besides the CPU ran
// (gpu_suite.hpp).
#include <cmath>
#include <utility>

#include "curvestereo/metrics.hpp"
#include "curvestereo/stereo.hpp"
#include "forwarding_backend.hpp"
#include "golden_cases.hpp"
#include "gpu_suite.hpp"
#include "synth/scene.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

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

// Every backend compiled in, the CPU first.
std::vector<std::string> everyBackend() {
  std::vector<std::string> names = otherBackends();
  names.insert(names.begin(), "cpu");
  return names;
}

// tryBackend, where the CPU always runs.
std::unique_ptr<Backend> usableBackend(const std::string& name) {
  return name == "cpu" ? createBackend("cpu") : tryBackend(name);
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
        const golden::Tolerance tol = expected[i].tolerance;  // the case's own (golden_cases.cpp)
        golden::Difference d = golden::compare(actual[i].planes, expected[i].planes, tol.maxAbs);
        MESSAGE(name << " " << actual[i].name << ": max abs " << d.maxAbs << ", NMSE " << d.nmse);
        CHECK(d.mismatchedNonFinite == 0);
        CHECK(d.maxAbs <= tol.maxAbs);
        CHECK(d.nmse <= tol.nmse);
      }
    }
  }
}

// Every 8-bit value, and a count that is no multiple of 4 (the CUDA kernel's word-wide
// path and its tail): stored exactly as the image readers store them.
TEST_CASE("uploadBytes stores unitFromByte(v) on every backend") {
  const int w = 19, h = 14;
  std::vector<uint8_t> bytes(size_t(w) * h);
  for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = uint8_t((i * 37 + 11) % 256);
  for (const std::string& name : everyBackend()) {
    auto backend = usableBackend(name);
    if (!backend) continue;
    const Buffer buffer = backend->create(w, h, 1);
    backend->fill(buffer, -1.f);
    backend->uploadBytes(buffer, bytes.data());
    std::vector<float> back(bytes.size());
    backend->download(buffer, back.data());
    size_t exact = 0;
    for (size_t i = 0; i < bytes.size(); ++i) exact += back[i] == unitFromByte(bytes[i]);
    INFO("backend " << name);
    CHECK(exact == bytes.size());
  }
}

// downloadAll brings back what one download() each would, whatever the buffers' sizes
// (the Vulkan staging claim, the CUDA pieces and their events), including a buffer twice and
// results of kernels still queued when it is called.
TEST_CASE("downloadAll returns each buffer as download() does on every backend") {
  for (const std::string& name : everyBackend()) {
    auto backend = usableBackend(name);
    if (!backend) continue;
    const Buffer a = backend->create(37, 11, 1), b = backend->create(5, 3, 2), c = backend->create(64, 48, 3);
    std::vector<float> va(a.count()), vb(b.count()), vc(c.count());
    for (size_t i = 0; i < va.size(); ++i) va[i] = float(i) * 0.5f;
    for (size_t i = 0; i < vc.size(); ++i) vc[i] = -float(i);
    backend->upload(a, va.data());
    backend->fill(b, 3.25f);
    backend->upload(c, vc.data());
    const Buffer d = backend->create(37, 11, 1);
    backend->copy(d, a);  // queued work before the downloads
    std::vector<float> ga(va.size(), NAN), gb(vb.size(), NAN), gc(vc.size(), NAN), gd(va.size(), NAN),
        ga2(va.size(), NAN);
    backend->downloadAll({{a, ga.data()}, {b, gb.data()}, {c, gc.data()}, {d, gd.data()}, {a, ga2.data()}});
    INFO("backend " << name);
    CHECK(ga == va);
    CHECK(gd == va);
    CHECK(ga2 == va);
    CHECK(gb == std::vector<float>(vb.size(), 3.25f));
    CHECK(gc == vc);
  }
}

// Buffers of several download pieces (1 MiB each on CUDA and Vulkan), one a float short
// of a piece and one a float over, between small ones: each comes back whole, in order,
// with its neighbours untouched.
TEST_CASE("downloadAll returns buffers of several pieces and odd sizes as download() does on every backend") {
  for (const std::string& name : everyBackend()) {
    auto backend = usableBackend(name);
    if (!backend) continue;
    const std::vector<Buffer> buffers = {backend->create(3, 1, 1), backend->create(700, 500, 2),
                                         backend->create(513, 511, 1), backend->create(262145, 1, 1),
                                         backend->create(7, 5, 3)};
    std::vector<std::vector<float>> values, expected, got;
    std::vector<Backend::Download> list;
    for (size_t k = 0; k < buffers.size(); ++k) {
      values.emplace_back(buffers[k].count());
      for (size_t i = 0; i < values[k].size(); ++i) values[k][i] = float(k) * 1e6f + float(i);
      backend->upload(buffers[k], values[k].data());
      expected.emplace_back(buffers[k].count(), NAN);
      got.emplace_back(buffers[k].count(), NAN);
    }
    for (size_t k = 0; k < buffers.size(); ++k) list.push_back({buffers[k], got[k].data()});
    backend->downloadAll(list);
    for (size_t k = 0; k < buffers.size(); ++k) backend->download(buffers[k], expected[k].data());
    INFO("backend " << name);
    for (size_t k = 0; k < buffers.size(); ++k) {
      INFO("buffer " << k);
      CHECK(got[k] == values[k]);
      CHECK(expected[k] == values[k]);
    }
  }
}

// Several byte uploads before one download (the Vulkan conversions' staged bytes side by
// side), of 1 to 5 samples (a partial word alone) and of images of many work groups.
TEST_CASE("uploadBytes of several images of odd sizes in a row stores unitFromByte(v) on every backend") {
  const std::vector<std::pair<int, int>> sizes = {{1, 1}, {2, 1}, {3, 1}, {4, 1}, {5, 1}, {333, 333}, {1000, 701}};
  for (const std::string& name : everyBackend()) {
    auto backend = usableBackend(name);
    if (!backend) continue;
    std::vector<Buffer> buffers;
    std::vector<std::vector<uint8_t>> bytes;
    for (size_t k = 0; k < sizes.size(); ++k) {
      buffers.push_back(backend->create(sizes[k].first, sizes[k].second, 1));
      backend->fill(buffers.back(), -1.f);
      bytes.emplace_back(buffers.back().count());
      for (size_t i = 0; i < bytes[k].size(); ++i) bytes[k][i] = uint8_t((i * 131 + k * 7 + 3) % 256);
    }
    for (size_t k = 0; k < sizes.size(); ++k) backend->uploadBytes(buffers[k], bytes[k].data());
    std::vector<std::vector<float>> back;
    std::vector<Backend::Download> list;
    for (const Buffer& b : buffers) back.emplace_back(b.count(), NAN);
    for (size_t k = 0; k < buffers.size(); ++k) list.push_back({buffers[k], back[k].data()});
    backend->downloadAll(list);
    INFO("backend " << name);
    for (size_t k = 0; k < sizes.size(); ++k) {
      size_t exact = 0;
      for (size_t i = 0; i < bytes[k].size(); ++i) exact += back[k][i] == unitFromByte(bytes[k][i]);
      INFO("image " << k);
      CHECK(exact == bytes[k].size());
    }
  }
}

// A camera's 8-bit images and the same images as floats are one input: bit-identical results.
TEST_CASE("8-bit images solve exactly as their float conversion on every backend") {
  synth::SynthConfig cfg;
  cfg.camera = synth::defaultFisheye(97);
  cfg.baseline = 0.12;
  cfg.seed = 4;
  cfg.samplesPerAxis = 1;
  const synth::SynthPair pair = synth::renderPair(cfg);
  auto toBytes = [](const ImageF& img) {
    ImageU8 out(img.width, img.height);
    for (size_t i = 0; i < img.size(); ++i)
      out.data[i] = uint8_t(std::lround(255.f * std::clamp(img.data[i], 0.f, 1.f)));
    return out;
  };
  auto toFloats = [](const ImageU8& img) {
    ImageF out(img.width, img.height);
    for (size_t i = 0; i < img.size(); ++i) out.data[i] = unitFromByte(img.data[i]);
    return out;
  };
  const ImageU8 leftBytes = toBytes(pair.left), rightBytes = toBytes(pair.right);
  const ImageF left = toFloats(leftBytes), right = toFloats(rightBytes);
  Params params = preset("realtime");
  params.minWidth = 20;
  for (const std::string& name : everyBackend()) {
    if (name != "cpu" && !tryBackend(name)) continue;
    Stereo stereo(pair.rig, params, name);
    const DepthResult fromFloats = stereo.compute(left, right);
    const DepthResult fromBytes = stereo.compute(leftBytes, rightBytes);
    stereo.resetSequence();
    stereo.next(left, right);
    const DepthResult nextFromFloats = stereo.next(left, right);
    stereo.resetSequence();
    stereo.next(leftBytes, rightBytes);
    const DepthResult nextFromBytes = stereo.next(leftBytes, rightBytes);
    INFO("backend " << name);
    CHECK(test::sameBits(fromBytes.depth.radial, fromFloats.depth.radial));
    CHECK(test::sameBits(fromBytes.confidence, fromFloats.confidence));
    CHECK(nextFromBytes.warm);
    CHECK(test::sameBits(nextFromBytes.depth.radial, nextFromFloats.depth.radial));
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
  for (const std::string& name : everyBackend()) {
    auto backend = usableBackend(name);
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
  for (const std::string& name : everyBackend()) {
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

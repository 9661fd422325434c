// The kernels' contracts (backend.hpp) are checked above the backends: on every backend
// present (the CPU oracle always; Vulkan on lavapipe here, CUDA on a GPU), a call that
// breaks one is refused with one line naming the backend, the kernel and the problem,
// before the backend touches a buffer.
#include <string>
#include <vector>

#include "curvestereo/backend.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/stereo.hpp"  // availableBackends
#include "test_util.hpp"

using namespace cs;

namespace {

// Every backend that can run here: the CPU always, the others when their device is usable.
std::vector<std::unique_ptr<Backend>> usableBackends() {
  std::vector<std::unique_ptr<Backend>> out;
  for (const std::string& name : availableBackends()) {
    try {
      out.push_back(createBackend(name));
    } catch (const Error& e) {
      MESSAGE("SKIPPED backend " << name << ": " << std::string(e.what()));
    }
  }
  return out;
}

// The message of the cs::Error `call` throws ("" when it throws none).
template <class F>
std::string refusal(F&& call) {
  try {
    call();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// Refused with one line "<backend> backend: <kernel>: ..." containing `needle`.
template <class F>
void checkRefused(const Backend& b, const std::string& kernel, const std::string& needle, F&& call) {
  const std::string what = refusal(call);
  INFO("backend " << b.name() << ", kernel " << kernel << ": " << what);
  CHECK(what.rfind(b.name() + " backend: " + kernel + ": ", 0) == 0);
  CHECK(what.find(needle) != std::string::npos);
  CHECK(what.find('\n') == std::string::npos);
}

}  // namespace

TEST_CASE("a kernel called with a wrong shape is refused with the kernel and the problem named") {
  for (auto& owned : usableBackends()) {
    Backend& b = *owned;
    MESSAGE("backend " << b.name() << ": " << b.device());
    const int w = 12, h = 9;
    const Buffer one = b.create(w, h, 1), other = b.create(w, h, 1), two = b.create(w, h, 2), two2 = b.create(w, h, 2),
                 four = b.create(w, h, 4), four2 = b.create(w, h, 4), narrow = b.create(w - 2, h, 1),
                 mask = b.create(w, h, 1);
    std::vector<float> ones(size_t(w) * h, 1.f);
    b.upload(mask, ones.data());

    // The CPU oracle used to read these out of bounds.
    checkRefused(b, "warp", "flow has 1 channel, expected 2", [&] { b.warp(one, other, mask); });
    checkRefused(b, "warp", "src has 2 channels, expected 1", [&] { b.warp(one, two, two2); });
    checkRefused(b, "median", "src is 10x9 but mask is 12x9", [&] { b.median(one, narrow, mask); });
    checkRefused(b, "median", "dst and src are the same buffer", [&] { b.median(one, one, mask); });
    const Buffer coarse = b.create(6, 5, 1), coarseW = b.create(6, 5, 2);
    checkRefused(b, "upsampleEstimate", "coarseW has 1 channel, expected 2", [&] {
      b.upsampleEstimate(one, two, coarse, coarse, one, other, mask, {2.f, 1.f, 2});
    });
    checkRefused(b, "upsampleEstimate", "scale must be above 1", [&] {
      b.upsampleEstimate(one, two, coarse, coarseW, one, other, mask, {1.f, 1.f, 2});
    });
    checkRefused(b, "upsampleEstimate", "radius 5 outside [0, 4]", [&] {
      b.upsampleEstimate(one, two, coarse, coarseW, one, other, mask, {2.f, 1.f, 5});
    });
    checkRefused(b, "accumulate", "w has 1 channel, expected 2",
                 [&] { b.accumulate(one, other, one, two, mask, 0.2f); });
    const PrimalDualBuffers pd{one, other, two, two2, b.create(w, h, 2), two};  // q: 2 channels
    const DataTermBuffers data{b.create(w, h, 1), b.create(w, h, 1), b.create(w, h, 1)};
    const PrimalDualParams prm{20.f, 17.f, 1.2f, {{1.f, 1.f, 1.f}}};
    checkRefused(b, "primalDual", "q has 2 channels, expected 4",
                 [&] { b.primalDual(pd, data, four, four2, mask, prm); });
    checkRefused(b, "warpIterations", "q has 2 channels, expected 4",
                 [&] { b.warpIterations(pd, data, four, four2, mask, prm); });
    checkRefused(b, "structureTensor", "steps has 2 channels, expected 4", [&] {
      b.structureTensor(four, two, one, mask, TensorParams{9.f, 0.85f, 1e-4f, 1.f, 17.f, 1.2f});
    });
    checkRefused(b, "structureTensor", "smoothing sigma", [&] {
      b.structureTensor(four, four2, one, mask, TensorParams{9.f, 0.85f, 1e-4f, 50.f, 17.f, 1.2f});
    });
    NormaliseParams np{};
    np.radius = kMaxNormaliseRadius + 1;
    checkRefused(b, "normalise", "radius 25 outside [0, 24]",
                 [&] { b.normalise(one, b.create(w, h, 3), other, mask, np); });
    checkRefused(b, "warpDerivatives", "confidence is 10x9 but mask is 12x9",
                 [&] { b.warpDerivatives(data, two, one, other, two2, two, one, mask, narrow, 0.3f); });
    // The coarse tail checks the next warp's data term only when there is one.
    const WarpBuffers warp{one, two, two2, mask, data, narrow, other, two, Buffer{}, 1.f};
    checkRefused(b, "warpTail", "i0 is 10x9 but mask is 12x9", [&] { b.warpTail(warp, Buffer{}, 0.2f, true); });
    checkRefused(b, "warpTail", "dst and src are the same buffer", [&] { b.warpTail(warp, one, 0.2f, false); });

    // The plane sweep: one plane cap for every backend.
    SweepParams sp{};
    sp.cam.model = 0, sp.cam.width = w, sp.cam.height = h;
    sp.cam.params[0] = sp.cam.params[1] = 5.0, sp.cam.params[2] = 5.5, sp.cam.params[3] = 4.0;
    sp.t[0] = -0.1, sp.qMax = 1.0, sp.radius = 1, sp.planes = kMaxSweepPlanes + 1;
    checkRefused(b, "sweepWarp", "needs 2 to " + std::to_string(kMaxSweepPlanes) + " planes, got 513",
                 [&] { b.sweepWarp(one, other, mask, sp); });
    sp.planes = 3;
    checkRefused(b, "sweepCost", "volume has 4 channels, expected 3",
                 [&] { b.sweepCost(b.create(w, h, 3), one, four, mask, sp); });
    // The band sweep: bands of 2 to 32 hypotheses, no more than the planes.
    sp.band = 4;
    checkRefused(b, "sweepBandCost", "needs a band of 2 to 3 hypotheses, got 4",
                 [&] { b.sweepBandCost(four, one, four, other, mask, sp); });
    sp.planes = 40, sp.band = kMaxSweepBand + 1;
    checkRefused(b, "sweepBandAggregate", "needs a band of 2 to 32 hypotheses, got 33",
                 [&] { b.sweepBandAggregate(four, b.create(w, h, 33), other, mask, sp); });
    sp.band = 3;
    checkRefused(b, "sweepBandWarp", "first is 10x9 but mask is 12x9",
                 [&] { b.sweepBandWarp(b.create(w, h, 3), narrow, other, two, mask, sp, 0.5f); });
    checkRefused(b, "sweepBandWarp", "needs a coarse scale in (0, 1], got 2",
                 [&] { b.sweepBandWarp(b.create(w, h, 3), one, other, two, mask, sp, 2.f); });
    checkRefused(b, "sweepBandSelect", "aggregated has 4 channels, expected 3",
                 [&] { b.sweepBandSelect(two, four, b.create(w, h, 3), one, mask, sp); });
    sp.planes = 3;
    sp.cam.model = 99;
    checkRefused(b, "sweepSelect", "unknown camera model 99",
                 [&] { b.sweepSelect(two, b.create(w, h, 3), b.create(w, h, 3), mask, sp); });

    // Buffers: unknown ids and shapes larger than created.
    checkRefused(b, "fill", "is not a buffer of this backend (id 12345)", [&] { b.fill(Buffer{12345, w, h, 1}, 0.f); });
    std::vector<float> host(size_t(4) * w * h);
    checkRefused(b, "upload", "larger than it was created (12x9x1)", [&] {
      b.upload(Buffer{one.id, w, 2 * h, 1}, host.data());
    });
    checkRefused(b, "copy", "differ in size", [&] { b.copy(one, two); });
    checkRefused(b, "create", "invalid buffer size 0x4x1", [&] { b.create(0, 4, 1); });

    // Nothing was written: the mask keeps its ones, and the backend stays usable.
    std::vector<float> back(ones.size(), 0.f);
    b.download(mask, back.data());
    CHECK(back == ones);
  }
}

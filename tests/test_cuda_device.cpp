// The CUDA device-pointer API (cs::cuda::DeviceStereo): inputs already on the GPU, results
// left there, work on the caller's stream. Checked against the host API on the same
// backend (same kernels: identical results) and against the CPU oracle. Skipped, with
// the reason, when the build has no CUDA or no device is present (reported to ctest as
// skipped: gpu_suite.hpp).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "curvestereo/stereo.hpp"
#include "gpu_suite.hpp"
#include "synth/scene.hpp"
#include "test_util.hpp"

#ifdef CS_HAVE_CUDA
#include <cuda_runtime.h>

#include "../backend_cuda/cuda_backend.hpp"
#include "curvestereo/cuda.hpp"
#include "golden_cases.hpp"
#endif

using namespace cs;

#ifndef CS_HAVE_CUDA
TEST_CASE("CUDA device-pointer API") { MESSAGE("SKIPPED: this build has no CUDA backend"); }
#else

namespace {

void ok(cudaError_t e) { REQUIRE_MESSAGE(e == cudaSuccess, cudaGetErrorString(e)); }

std::vector<float> fetch(const float* dev, size_t count, cudaStream_t stream) {
  std::vector<float> host(count);
  ok(cudaMemcpyAsync(host.data(), dev, count * sizeof(float), cudaMemcpyDeviceToHost, stream));
  ok(cudaStreamSynchronize(stream));
  return host;
}

// Whether a device output equals the host API's bit for bit, NaN included.
bool sameBits(const std::vector<float>& device, const void* host, size_t bytes) {
  return device.size() * sizeof(float) == bytes && std::memcmp(device.data(), host, bytes) == 0;
}

// True (and the reason reported) when no CUDA device can run these tests.
bool noDevice(const char* what) {
  const std::string why = cuda::probe();
  const std::string skipped = std::string("SKIPPED ") + what + ": " + why;  // not the pointer `what`
  if (!why.empty()) MESSAGE(skipped);
  if (why.empty()) test::gpuUsed();
  return !why.empty();
}

synth::SynthPair smallPair(uint32_t seed) {
  synth::SynthConfig cfg;
  cfg.camera = synth::defaultFisheye(121);
  cfg.camera.height = 113;
  cfg.camera.params[3] = 56.0;
  cfg.baseline = 0.12;
  cfg.seed = seed;
  cfg.samplesPerAxis = 2;
  return synth::renderPair(cfg);
}

// The primal-dual paths at one level size against the oracle (see the test case below).
void checkPrimalDualPaths(int w, int h) {
  const size_t n = size_t(w) * h;
  auto noise = [&](int channels, uint32_t seed, float amp) {
    std::vector<float> v(n * size_t(channels));
    for (size_t i = 0; i < v.size(); ++i) v[i] = amp * (2.f * golden::hash01(uint32_t(i) * 2891336453U + seed) - 1.f);
    return v;
  };
  std::vector<float> image(n), mask(n);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      image[i] = 0.5f + 0.3f * std::sin(0.21f * x) * std::cos(0.17f * y) + 0.05f * golden::hash01(uint32_t(i) + 99U);
      const bool inDisc = std::hypot(x - 0.5 * (w - 1), y - 0.5 * (h - 1)) <= 0.47 * std::min(w, h);
      mask[i] = inDisc && golden::hash01(uint32_t(i) * 7U + 3U) > 0.03f ? 1.f : 0.f;
    }
  auto cpu = createBackend("cpu");
  std::vector<float> tensor(4 * n), steps(4 * n);
  {
    const Buffer t = cpu->create(w, h, 4), st = cpu->create(w, h, 4), im = cpu->create(w, h, 1),
                 m = cpu->create(w, h, 1);
    cpu->upload(im, image.data());
    cpu->upload(m, mask.data());
    cpu->structureTensor(t, st, im, m, TensorParams{9.f, 0.85f, 1e-4f, 1.f, 17.f, 1.2f});
    cpu->download(t, tensor.data());
    cpu->download(st, steps.data());
  }
  const std::vector<float> u = noise(1, 11, 1.f), v = noise(2, 12, 0.1f), p = noise(2, 13, 0.5f),
                           q = noise(4, 14, 0.2f), u0 = noise(1, 15, 1.f), iu = noise(1, 16, 0.1f),
                           iz = noise(1, 17, 0.05f), uBar = noise(1, 18, 1.f), vBar = noise(2, 19, 0.1f);
  // u, uBar, v, vBar, p, q after the solve. copyBars: warpIterations (uBar = u, vBar = v
  // first, as the pipeline does at every warp; the CUDA backend folds those copies into the
  // first launch) in place of primalDual.
  auto solve = [&](Backend& b, int iterations, bool copyBars) {
    auto put = [&](const std::vector<float>& host, int channels) {
      const Buffer buf = b.create(w, h, channels);
      b.upload(buf, host.data());
      return buf;
    };
    const PrimalDualBuffers pd{put(u, 1), put(uBar, 1), put(v, 2), put(vBar, 2), put(p, 2), put(q, 4)};
    const DataTermBuffers data{put(u0, 1), put(iu, 1), put(iz, 1)};
    const PrimalDualParams prm = golden::primalDualCaseParams(iterations);
    const Buffer tensorBuf = put(tensor, 4), stepsBuf = put(steps, 4), maskBuf = put(mask, 1);
    if (copyBars)
      b.warpIterations(pd, data, tensorBuf, stepsBuf, maskBuf, prm);
    else
      b.primalDual(pd, data, tensorBuf, stepsBuf, maskBuf, prm);
    std::vector<std::vector<float> > out;
    for (const Buffer& buf : {pd.u, pd.uBar, pd.v, pd.vBar, pd.p, pd.q}) {
      out.emplace_back(buf.count());
      b.download(buf, out.back().data());
    }
    return out;
  };
  // 4 iterations in launches of two end in the first set (the pixels outside the mask are
  // copied by the first launch only); 6 and 7 in launches of five leave one or two over.
  for (int iterations : {3, 4, 5, 6, 7, 10, 70})
    for (bool copyBars : {false, true}) {
      const auto ref = solve(*cpu, iterations, copyBars);
      for (bool fiveIterationLaunches : {true, false}) {
        cuda::CudaBackend cuda(0);
        // Five iterations per launch (where the level's tiles fit on the device at once: every
        // size here on an H100 / H200), then two.
        cuda.setFiveIterationLaunches(fiveIterationLaunches);
        const auto out = solve(cuda, iterations, copyBars);
        double maxAbs = 0;
        long long nonFinite = 0;
        for (size_t b = 0; b < out.size(); ++b)
          for (size_t i = 0; i < out[b].size(); ++i) {
            if (!std::isfinite(out[b][i]))
              ++nonFinite;
            else
              maxAbs = std::max(maxAbs, double(std::abs(out[b][i] - ref[b][i])));
          }
        const std::string name = fiveIterationLaunches ? "five iterations per launch" : "two per launch";
        MESSAGE("primal-dual " << name << ", " << w << "x" << h << ", " << iterations << " iterations"
                               << std::string(copyBars ? " after uBar = u" : "") << ": max abs " << maxAbs
                               << " against the oracle");
        CHECK(nonFinite == 0);
        CHECK(maxAbs <= 1e-4);
      }
    }
}

}  // namespace

TEST_CASE("CUDA device-pointer API: device inputs and outputs on a user stream") {
  if (noDevice("cuda device API")) return;
  const synth::SynthPair pair = smallPair(21);
  Params params = preset("variational");
  params.minWidth = 20;
  params.warps = 8;
  const int w = pair.left.width, h = pair.left.height;
  const size_t n = size_t(w) * h;

  Stereo host(pair.rig, params, "cuda");
  const DepthResult ref = host.compute(pair.left, pair.right);
  Stereo oracle(pair.rig, params, "cpu");
  const DepthResult cpu = oracle.compute(pair.left, pair.right);

  cudaStream_t stream = nullptr;
  ok(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
  // Pitched inputs: rows padded, as images from a camera driver or another library are.
  float *left = nullptr, *right = nullptr;
  size_t pitch = 0, pitchRight = 0;
  ok(cudaMallocPitch(reinterpret_cast<void**>(&left), &pitch, w * sizeof(float), h));
  ok(cudaMallocPitch(reinterpret_cast<void**>(&right), &pitchRight, w * sizeof(float), h));
  REQUIRE(pitch == pitchRight);
  ok(cudaMemcpy2D(left, pitch, pair.left.data.data(), w * sizeof(float), w * sizeof(float), h, cudaMemcpyHostToDevice));
  ok(cudaMemcpy2D(right, pitch, pair.right.data.data(), w * sizeof(float), w * sizeof(float), h,
                  cudaMemcpyHostToDevice));
  {
    cuda::DeviceStereo dev(pair.rig, params, stream);
    CHECK(dev.stream() == stream);
    // Frames 1-3: run directly, recorded into a graph, replayed.
    cuda::DeviceDepth first;
    for (int frame = 0; frame < 3; ++frame) {
      const cuda::DeviceDepth d = dev.compute(left, right, pitch);
      REQUIRE(d.width == w);
      REQUIRE(d.height == h);
      // The outputs stay where the first frame put them (the backend moves buffers between
      // memory blocks inside a frame), as DeviceDepth promises.
      if (frame == 0) first = d;
      CHECK(d.valid == first.valid);
      CHECK(d.disparity == first.disparity);
      CHECK(d.warp == first.warp);
      CHECK(d.radial == first.radial);
      CHECK(d.points == first.points);
      const std::vector<float> valid = fetch(d.valid, n, stream), u = fetch(d.disparity, n, stream),
                               radial = fetch(d.radial, n, stream), warp = fetch(d.warp, 2 * n, stream);
      long long mismatches = 0, validCount = 0, close = 0;
      for (size_t i = 0; i < n; ++i) {
        const bool v = valid[i] != 0.f;
        mismatches += v != bool(ref.valid.data[i]);
        if (!v || !ref.valid.data[i]) {
          CHECK(std::isnan(radial[i]));
          continue;
        }
        ++validCount;
        // Same backend, same kernels: the same numbers as the host API.
        mismatches +=
            u[i] != ref.disparity.data[i] || warp[2 * i] != ref.warp.data[i].x || warp[2 * i + 1] != ref.warp.data[i].y;
        mismatches += !(radial[i] == ref.depth.radial.data[i]);
        close += std::abs(u[i] - cpu.disparity.data[i]) <= 0.05f;
      }
      MESSAGE("frame " << frame << ": " << validCount << " valid, " << mismatches << " differ from the host API, "
                       << 100.0 * close / double(std::max(1LL, validCount)) << " % within 0.05 px of the oracle");
      // The same finishing kernel (Backend::finishResult): every output is the host API's,
      // bit for bit, NaN and infinity included.
      CHECK(sameBits(radial, ref.depth.radial.data.data(), n * 4));
      CHECK(sameBits(u, ref.disparity.data.data(), n * 4));
      CHECK(sameBits(warp, ref.warp.data.data(), n * 8));
      CHECK(sameBits(fetch(d.points, 3 * n, stream), ref.depth.points.data.data(), n * 12));
      CHECK(sameBits(fetch(d.z, n, stream), ref.depth.z.data.data(), n * 4));
      CHECK(sameBits(fetch(d.confidence, n, stream), ref.confidence.data.data(), n * 4));
      CHECK(validCount > 0);
      CHECK(mismatches == 0);
      CHECK(double(close) >= 0.99 * double(validCount));
    }
    // A new pose drops the recorded frame: the results follow the pose as on the host path.
    const Eigen::Vector3d t2 = pair.rig.t * 1.25;
    dev.setPose(pair.rig.R, t2);
    host.setPose(pair.rig.R, t2);
    const DepthResult ref2 = host.compute(pair.left, pair.right);
    for (int frame = 0; frame < 2; ++frame) {
      const cuda::DeviceDepth d = dev.compute(left, right, pitch);
      const std::vector<float> radial = fetch(d.radial, n, stream);
      long long mismatches = 0;
      for (size_t i = 0; i < n; ++i)
        if (ref2.valid.data[i]) mismatches += !(radial[i] == ref2.depth.radial.data[i]);
      CHECK(mismatches == 0);
    }
  }
  cudaFree(left);
  cudaFree(right);
  cudaStreamDestroy(stream);
}

// primalDual runs five iterations per launch on levels whose tiles then fit on the device
// at once, and two otherwise: both paths, schedules that end in either set and with
// iterations left over, with and without the pipeline's uBar = u copies, against the
// oracle on random state over several tiles with ragged edges and a masked disc.
TEST_CASE("CUDA primal-dual: launches of five and of two iterations match the oracle") {
  if (noDevice("cuda primal-dual paths")) return;
  for (const auto& [w, h] : {std::pair{61, 45}, std::pair{64, 64}, std::pair{90, 70}, std::pair{203, 131}})
    checkPrimalDualPaths(w, h);
}

TEST_CASE("CUDA device-pointer API: the initialiser's confidence stays on the device, as the host API gives it") {
  if (noDevice("cuda device API")) return;
  const synth::SynthPair pair = smallPair(23);
  Params params = preset("quality");
  params.minWidth = 20;
  params.warps = 4;
  const int w = pair.left.width, h = pair.left.height;
  const size_t n = size_t(w) * h;
  cudaStream_t stream = nullptr;
  ok(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
  float* images = nullptr;
  ok(cudaMalloc(&images, 2 * n * sizeof(float)));
  ok(cudaMemcpy(images, pair.left.data.data(), n * sizeof(float), cudaMemcpyHostToDevice));
  ok(cudaMemcpy(images + n, pair.right.data.data(), n * sizeof(float), cudaMemcpyHostToDevice));
  {
    Stereo host(pair.rig, params, "cuda");
    const DepthResult ref = host.compute(pair.left, pair.right);
    cuda::DeviceStereo dev(pair.rig, params, stream);
    for (int frame = 0; frame < 2; ++frame) {
      const cuda::DeviceDepth d = dev.compute(images, images + n);
      REQUIRE(d.confidence != nullptr);
      const std::vector<float> confidence = fetch(d.confidence, n, stream);
      long long valid = 0, differ = 0;
      for (size_t i = 0; i < n; ++i) {
        if (!ref.valid.data[i]) continue;
        ++valid;
        differ += !(confidence[i] == ref.confidence.data[i]) || confidence[i] < 0.f || confidence[i] > 1.f;
      }
      CHECK(valid > 0);
      CHECK(differ == 0);
    }
    cuda::DeviceStereo without(pair.rig, preset("variational"), stream);
    CHECK(without.compute(images, images + n).confidence != nullptr);  // every preset has one
  }
  cudaFree(images);
  cudaStreamDestroy(stream);
}

namespace {

// The largest difference between two outputs and the number of values finite in one only.
struct Difference {
  double maxAbs = 0;
  long long nonFinite = 0;
};
Difference difference(const std::vector<float>& a, const std::vector<float>& b) {
  Difference d;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::isfinite(a[i]) != std::isfinite(b[i]))
      ++d.nonFinite;
    else if (std::isfinite(a[i]))
      d.maxAbs = std::max(d.maxAbs, double(std::abs(a[i] - b[i])));
    else if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i]))))
      ++d.nonFinite;
  }
  return d;
}

// Rotation about y by `angle` (rad), row-major, then t: a motion buffer's floats.
std::vector<float> motionFloats(double angle, const Eigen::Vector3d& t) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {float(c), 0.f, float(s), 0.f, 1.f, 0.f, float(-s), 0.f, float(c), float(t.x()), float(t.y()), float(t.z())};
}

}  // namespace

// Backend::beginFrame's slots: two kinds of frame (the carries of a warm start; the prior
// and the temporal filter), each recorded in its own slot and replayed, interleaved. Between
// frames, as a sequence does: the motion uploaded (read by the recorded kernels, not baked
// into them), the state reset by fill() or committed by copy() and an input uploaded after
// it (queued work runs before the frame, in order, and is never recorded into it). Each
// frame's outputs against the oracle running the same calls.
TEST_CASE("CUDA frame slots: each kind of frame replays with the frame's motion and state") {
  if (noDevice("cuda frame slots")) return;
  const synth::SynthPair pair = smallPair(25);
  const CameraParams cam = toCameraParams(pair.rig.cam0), half = toCameraParams(pair.rig.cam0.scaled(0.5));
  const int w = cam.width, h = cam.height;
  const size_t n = size_t(w) * h, nHalf = size_t(half.width) * half.height;
  const Eigen::Vector3d tPrime = pair.rig.R.transpose() * pair.rig.t;
  // Frame k's state (inverse depth 0.15 .. 0.55 /m, some pixels without an estimate), the
  // measurement (radial depth with NaN, +inf and negative pixels) and its confidence.
  auto stateAt = [&](int k) {
    std::vector<float> v(2 * n);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        const bool none = golden::hash01(uint32_t(i) * 13U + uint32_t(k)) < 0.05f;
        v[2 * i] = none ? -1.f : 0.35f + 0.2f * std::sin(0.05f * x + 0.3f * k) * std::cos(0.07f * y);
        v[2 * i + 1] = 0.2f + 0.5f * golden::hash01(uint32_t(i) + 7U * uint32_t(k));
      }
    return v;
  };
  std::vector<float> radial(n), confidence(n), ones(n, 1.f), onesHalf(nHalf, 1.f), u0(n), w0(2 * n);
  for (size_t i = 0; i < n; ++i) {
    const float q = 0.35f + 0.2f * golden::hash01(uint32_t(i) * 3U + 1U);
    radial[i] = i % 97 == 0 ? std::nanf("") : i % 89 == 0 ? INFINITY : i % 83 == 0 ? -1.f : 1.f / q;
    confidence[i] = golden::hash01(uint32_t(i) * 5U + 2U);
    u0[i] = 3.f * golden::hash01(uint32_t(i) + 11U);
    w0[2 * i] = u0[i];
    w0[2 * i + 1] = 0.1f;
  }
  constexpr int kFrames = 9;
  // Per frame: carried (full and half resolution), or prior, filtered state, u and w.
  auto run = [&](Backend& b) {
    auto put = [&](const std::vector<float>& host, int bw, int bh, int channels) {
      const Buffer buf = b.create(bw, bh, channels);
      b.upload(buf, host.data());
      return buf;
    };
    const Buffer state = b.create(w, h, 2), next = put(stateAt(0), w, h, 2), motion = b.create(kMotionFloats, 1, 1);
    const Buffer mask = put(ones, w, h, 1), maskHalf = put(onesHalf, half.width, half.height, 1);
    const Buffer guess = put(radial, w, h, 1), weight = put(confidence, w, h, 1), points = b.create(w, h, 3);
    const Buffer carried = b.create(w, h, 2), carriedHalf = b.create(half.width, half.height, 2);
    const Buffer prior = b.create(w, h, 2), filtered = b.create(w, h, 2), u = b.create(w, h, 1),
                 flow = b.create(w, h, 2);
    std::vector<std::vector<std::vector<float> > > out;
    for (int k = 0; k < kFrames; ++k) {
      // Between frames: reset or commit, the next input after it, u and w afresh, the motion.
      if (k % 4 == 0)
        b.fill(state, -1.f);
      else
        b.copy(state, next);
      b.upload(next, stateAt(k + 1).data());
      b.upload(u, u0.data());
      b.upload(flow, w0.data());
      b.upload(motion, motionFloats(0.02 * (k % 3 - 1), Eigen::Vector3d(0.05 * (k % 2), 0.01, -0.02 * (k % 3))).data());
      const int slot = k % 3 == 2 ? 1 : 0;
      if (b.canReplayFrame(slot)) {
        b.replayFrame(slot);
      } else {
        b.beginFrame(slot);
        if (slot == 0) {
          b.carryEstimate(carried, state, Buffer{}, motion, mask, {cam, cam, {0, 0, 0}, 3});
          b.carryEstimate(carriedHalf, state, Buffer{}, motion, maskHalf,
                          {cam, half, {tPrime.x(), tPrime.y(), tPrime.z()}, 3});
        } else {
          b.carryEstimate(prior, state, guess, motion, mask, {cam, cam, {0, 0, 0}, 1});
          b.temporalFilter(filtered, u, flow, prior, guess, points, weight, mask,
                           {cam, {tPrime.x(), tPrime.y(), tPrime.z()}, 0.8f, 3.f, 0.5f, 0.1f, 0.1f});
        }
        b.endFrame();
      }
      std::vector<std::vector<float> > frame;
      for (const Buffer& buf :
           slot == 0 ? std::vector<Buffer>{carried, carriedHalf} : std::vector<Buffer>{prior, filtered, u, flow}) {
        frame.emplace_back(buf.count());
        b.download(buf, frame.back().data());
      }
      out.push_back(frame);
    }
    return out;
  };
  auto cpu = createBackend("cpu");
  const auto ref = run(*cpu);
  cuda::CudaBackend cudaBackend(0);
  const auto got = run(cudaBackend);
  CHECK(cudaBackend.canReplayFrame(0));
  CHECK(cudaBackend.canReplayFrame(1));
  for (int k = 0; k < kFrames; ++k) {
    long long estimates = 0;
    for (size_t i = 0; i < got[size_t(k)].size(); ++i) {
      const Difference d = difference(got[size_t(k)][i], ref[size_t(k)][i]);
      if (i == 0)
        for (size_t p = 0; p < ref[size_t(k)][0].size(); p += 2) estimates += ref[size_t(k)][0][p] >= 0.f;
      INFO("frame " << k << ", output " << i);
      CHECK(d.nonFinite == 0);
      CHECK(d.maxAbs <= 1e-4);
    }
    MESSAGE("frame " << k << " (slot " << (k % 3 == 2 ? 1 : 0) << "): " << estimates << " pixels with an estimate");
    if (k % 4 != 0) CHECK(estimates > 0);  // a reset frame carries nothing
  }
}

// DeviceStereo::next: with coldEvery 3 a sequence goes cold, warm, warm, cold, ...: the cold
// and the warm frame (both temporally filtered) each run directly, are recorded into their
// slots and replayed, interleaved. Every frame against cs::Stereo::next on the same backend
// (the same kernels and graphs: identical) and on the CPU oracle.
TEST_CASE("CUDA device-pointer API: a sequence's cold and warm frames as cs::Stereo::next gives them") {
  if (noDevice("cuda device sequences")) return;
  synth::SynthConfig cfg;
  cfg.camera = synth::defaultFisheye(161);
  cfg.baseline = 0.12;
  cfg.seed = 9;
  cfg.samplesPerAxis = 2;
  const synth::SynthPair pair = synth::renderPair(cfg);
  Params params = preset("realtime");
  params.minWidth = 20;
  params.coldEvery = 3;
  // The host API checks each warm frame and may solve it again cold; the device API cannot
  // (no readback). With no warm frame judged failed both follow the schedule alone.
  params.warmFailRatio = 0.f;
  const int w = pair.left.width, h = pair.left.height;
  const size_t n = size_t(w) * h;
  cudaStream_t stream = nullptr;
  ok(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
  float* images = nullptr;
  ok(cudaMalloc(&images, 2 * n * sizeof(float)));
  ok(cudaMemcpy(images, pair.left.data.data(), n * sizeof(float), cudaMemcpyHostToDevice));
  ok(cudaMemcpy(images + n, pair.right.data.data(), n * sizeof(float), cudaMemcpyHostToDevice));
  {
    Stereo host(pair.rig, params, "cuda"), oracle(pair.rig, params, "cpu");
    cuda::DeviceStereo dev(pair.rig, params, stream);
    const Pose pose;  // a static camera: the same pose every frame
    // The schedule, then a new sequence (cold again).
    const std::vector<bool> warmSchedule = {false, true, true, false, true, true, false, true, false};
    const size_t resetBefore = 8;
    cuda::DeviceDepth first;
    for (size_t frame = 0; frame < warmSchedule.size(); ++frame) {
      if (frame == resetBefore) {
        dev.resetSequence();
        host.resetSequence();
        oracle.resetSequence();
      }
      const cuda::DeviceDepth d = dev.next(images, images + n, &pose);
      const DepthResult ref = host.next(pair.left, pair.right, &pose);
      const DepthResult cpu = oracle.next(pair.left, pair.right, &pose);
      INFO("frame " << frame);
      CHECK(d.warm == warmSchedule[frame]);
      CHECK(ref.warm == warmSchedule[frame]);
      CHECK(cpu.warm == warmSchedule[frame]);
      CHECK_FALSE(ref.redone);
      CHECK_FALSE(cpu.redone);
      if (frame == 0) first = d;
      CHECK(d.valid == first.valid);
      CHECK(d.disparity == first.disparity);
      CHECK(d.radial == first.radial);
      const std::vector<float> valid = fetch(d.valid, n, stream), u = fetch(d.disparity, n, stream),
                               radial = fetch(d.radial, n, stream);
      long long validCount = 0, differ = 0, close = 0, validDiffer = 0;
      for (size_t i = 0; i < n; ++i) {
        const bool v = valid[i] != 0.f;
        validDiffer += v != bool(cpu.valid.data[i]);
        differ += v != bool(ref.valid.data[i]);
        differ +=
            !(radial[i] == ref.depth.radial.data[i] || (std::isnan(radial[i]) && std::isnan(ref.depth.radial.data[i])));
        if (!v || !ref.valid.data[i]) continue;
        ++validCount;
        differ += u[i] != ref.disparity.data[i];
        if (cpu.valid.data[i]) close += std::abs(u[i] - cpu.disparity.data[i]) <= 0.05f;
      }
      MESSAGE("sequence frame " << frame << (d.warm ? " (warm)" : " (cold)") << ": " << validCount << " valid, "
                                << differ << " values differ from the host API, "
                                << 100.0 * close / double(std::max(1LL, validCount))
                                << " % within 0.05 px of the oracle");
      CHECK(validCount > 0);
      CHECK(differ == 0);
      CHECK(validDiffer == 0);
      // The first frame is a pair's solve; later ones carry the backends' small differences
      // from frame to frame (the carry's nearest pixel, the band sweep's proposals).
      CHECK(double(close) >= (frame == 0 ? 0.99 : 0.98) * double(validCount));
    }
  }
  cudaFree(images);
  cudaStreamDestroy(stream);
}

TEST_CASE("CUDA device-pointer API refuses what it cannot run") {
  // The validation is cs::Stereo's own code (detail::StereoCore), given before any device is
  // needed, and the device API's own: both images at one resolution.
  {
    Rig bad = smallPair(3).rig;
    bad.cam1 = bad.cam1.scaled(0.5);
    std::string stereoWhy;
    try {
      Stereo stereo(bad, preset("variational"), "cpu");
    } catch (const Error& e) {
      stereoWhy = e.what();
    }
    CHECK(stereoWhy.empty());  // Stereo takes cameras of two resolutions; the device API's one pitch does not
    std::string deviceWhy;
    try {
      cuda::DeviceStereo device(bad, preset("variational"));
    } catch (const Error& e) {
      deviceWhy = e.what();
    }
    CHECK(deviceWhy.find("DeviceStereo needs both cameras at one resolution") != std::string::npos);
  }
  const std::string why = cuda::probe();
  if (!why.empty()) {
    MESSAGE("SKIPPED cuda device API: " << why);
    CHECK_THROWS_AS(cuda::DeviceStereo(smallPair(3).rig, preset("variational")), Error);
    return;
  }
  const synth::SynthPair pair = smallPair(3);
  test::gpuUsed();
  CHECK_THROWS_AS(cuda::DeviceStereo(pair.rig, preset("variational"), cudaStreamLegacy), Error);
  cuda::DeviceStereo dev(pair.rig, preset("variational"));
  CHECK_THROWS_AS(dev.compute(nullptr, nullptr), Error);
  CHECK_THROWS_AS(dev.next(nullptr, nullptr), Error);
  // setMask as Stereo's: the size checked, the pipeline kept.
  CHECK_THROWS_WITH_AS(dev.setMask(ImageU8(7, 5, 1)), doctest::Contains("mask is 7x5 but the images are"), Error);
  dev.setMask(ImageU8(pair.left.width, pair.left.height, 1));
}
#endif

// The CUDA device-pointer API (cs::cuda::DeviceStereo): inputs already on the GPU, results
// left there, work on the caller's stream. Checked against the host API on the same
// backend (same kernels: identical results) and against the CPU oracle. Skipped, with
// the reason, when the build has no CUDA or no device is present.
#include <cmath>
#include <vector>

#include "curvestereo/stereo.hpp"
#include "synth/scene.hpp"
#include "test_util.hpp"

#ifdef CS_HAVE_CUDA
#include <cuda_runtime.h>

#include "curvestereo/cuda.hpp"
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

}  // namespace

TEST_CASE("CUDA device-pointer API: device inputs and outputs on a user stream") {
  const std::string why = cuda::probe();
  if (!why.empty()) {
    MESSAGE("SKIPPED cuda device API: " << why);
    return;
  }
  const synth::SynthPair pair = smallPair(21);
  Params params = preset("default");
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
    for (int frame = 0; frame < 3; ++frame) {
      const cuda::DeviceDepth d = dev.compute(left, right, pitch);
      REQUIRE(d.width == w);
      REQUIRE(d.height == h);
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
        mismatches += u[i] != ref.disparity.data[i] || warp[2 * i] != ref.warp.data[i].x ||
                      warp[2 * i + 1] != ref.warp.data[i].y;
        mismatches += !(radial[i] == ref.depth.radial.data[i]);
        close += std::abs(u[i] - cpu.disparity.data[i]) <= 0.05f;
      }
      MESSAGE("frame " << frame << ": " << validCount << " valid, " << mismatches << " differ from the host API, "
                       << 100.0 * close / double(std::max(1LL, validCount)) << " % within 0.05 px of the oracle");
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

TEST_CASE("CUDA device-pointer API refuses what it cannot run") {
  const std::string why = cuda::probe();
  if (!why.empty()) {
    MESSAGE("SKIPPED cuda device API: " << why);
    CHECK_THROWS_AS(cuda::DeviceStereo(smallPair(3).rig, preset("default")), Error);
    return;
  }
  const synth::SynthPair pair = smallPair(3);
  CHECK_THROWS_AS(cuda::DeviceStereo(pair.rig, preset("default"), cudaStreamLegacy), Error);
  cuda::DeviceStereo dev(pair.rig, preset("default"));
  CHECK_THROWS_AS(dev.compute(nullptr, nullptr), Error);
}
#endif

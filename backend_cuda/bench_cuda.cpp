// curvestereo_cuda_bench: the CUDA device-pointer path timed end to end per frame, as a
// robot would run it: pinned host pair -> device (async), DeviceStereo::compute on one
// stream, radial depth -> pinned host, synchronise. Median / min / max over --runs frames
// after 3 warm-up frames (direct, recorded, first replay). --sequence N then times N
// consecutive frames of a sequence (DeviceStereo::next) on the same pair, as a static
// camera sees it (warm frames after each cold one), after a warm-up that records every kind
// of frame: the medians of the warm and of the cold frames, each end to end and GPU only.
//
//   curvestereo_cuda_bench --calib CAMCHAIN LEFT.png RIGHT.png [--preset NAME]
//                          [--levels L] [--warps N] [--iterations K] [--runs R] [--sequence N]
//                          [--param NAME=NUMBER ...]   (any numeric parameter, e.g. warm_band=8)
//
// The pair comes from files, as a robot's would, so that the bench needs the library alone;
// a synthetic one of any size is `curvestereo synth -o DIR --size N --samples 1` (or
// `--calib CAMCHAIN --size WIDTH` for another rig's lenses, e.g. the T265's 848x800).
#include <cuda_runtime.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "curvestereo/cuda.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/param_table.hpp"
#include "curvestereo/rig.hpp"

namespace {

void ok(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw cs::Error(std::string(what) + ": " + cudaGetErrorString(e));
}

}  // namespace

int main(int argc, char** argv) try {
  std::string preset = "realtime", calib, leftPath, rightPath;
  int levels = -1, warps = -1, iterations = -1, runs = 50, sequence = 0;
  std::vector<std::string> overrides;  // --param NAME=NUMBER, any numeric parameter of the table
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw cs::Error("option " + a + " needs a value");
      return argv[++i];
    };
    if (a == "--preset")
      preset = next();
    else if (a == "--levels")
      levels = std::stoi(next());
    else if (a == "--warps")
      warps = std::stoi(next());
    else if (a == "--iterations")
      iterations = std::stoi(next());
    else if (a == "--runs")
      runs = std::stoi(next());
    else if (a == "--sequence")
      sequence = std::stoi(next());
    else if (a == "--param")
      overrides.push_back(next());
    else if (a == "--calib") {
      calib = next();
      leftPath = next();
      rightPath = next();
    } else
      throw cs::Error("unknown option " + a);
  }
  cs::Params params = cs::preset(preset);
  if (levels > 0) params.levels = levels;
  if (warps > 0) params.warps = warps;
  if (iterations > 0) params.iterations = iterations;
  for (const std::string& o : overrides) {
    const size_t eq = o.find('=');
    if (eq == std::string::npos) throw cs::Error("--param needs NAME=VALUE, got '" + o + "'");
    cs::paramInfo(o.substr(0, eq)).setNumber(params, std::stod(o.substr(eq + 1)));
  }
  params.validate();

  if (calib.empty())
    throw cs::Error("needs --calib CAMCHAIN LEFT.png RIGHT.png (a synthetic pair: curvestereo synth -o DIR --size N)");
  const cs::Rig rig = cs::loadKalibr(calib);
  const cs::ImageF left = cs::readPngGray(leftPath), right = cs::readPngGray(rightPath);
  const std::string what = calib;
  const int w = left.width, h = left.height;
  const size_t n = size_t(w) * h;

  cudaStream_t stream = nullptr;
  ok(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking), "cudaStreamCreate");
  cs::cuda::DeviceStereo stereo(rig, params, stream);
  float *hPair = nullptr, *hDepth = nullptr, *dPair = nullptr;
  ok(cudaMallocHost(&hPair, 2 * n * sizeof(float)), "cudaMallocHost");
  ok(cudaMallocHost(&hDepth, n * sizeof(float)), "cudaMallocHost");
  ok(cudaMalloc(&dPair, 2 * n * sizeof(float)), "cudaMalloc");
  std::memcpy(hPair, left.data.data(), n * sizeof(float));
  std::memcpy(hPair + n, right.data.data(), n * sizeof(float));

  std::printf("device:   %s\n", stereo.deviceName().c_str());
  std::printf("input:    %s, %dx%d\n", what.c_str(), w, h);
  std::printf("settings: %s\n", cs::describe(params).c_str());
  std::printf("path:     device pointers; per frame: pair H2D (pinned, async), solve (CUDA graph), radial depth D2H\n");

  auto frame = [&] {
    ok(cudaMemcpyAsync(dPair, hPair, 2 * n * sizeof(float), cudaMemcpyHostToDevice, stream), "upload");
    const cs::cuda::DeviceDepth d = stereo.compute(dPair, dPair + n);
    ok(cudaMemcpyAsync(hDepth, d.radial, n * sizeof(float), cudaMemcpyDeviceToHost, stream), "download");
    ok(cudaStreamSynchronize(stream), "synchronize");
  };
  for (int i = 0; i < 3; ++i) frame();
  std::vector<double> ms;
  for (int i = 0; i < runs; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    frame();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  // GPU-only time of the solve (graph replay), from events, for reference.
  cudaEvent_t e0, e1;
  ok(cudaEventCreate(&e0), "cudaEventCreate");
  ok(cudaEventCreate(&e1), "cudaEventCreate");
  std::vector<double> solveMs;
  for (int i = 0; i < runs; ++i) {
    ok(cudaEventRecord(e0, stream), "cudaEventRecord");
    stereo.compute(dPair, dPair + n);
    ok(cudaEventRecord(e1, stream), "cudaEventRecord");
    ok(cudaEventSynchronize(e1), "cudaEventSynchronize");
    float t = 0.f;
    ok(cudaEventElapsedTime(&t, e0, e1), "cudaEventElapsedTime");
    solveMs.push_back(t);
  }
  long long finite = 0;
  std::vector<float> depths;
  for (size_t i = 0; i < n; ++i)
    if (std::isfinite(hDepth[i])) ++finite, depths.push_back(hDepth[i]);
  std::sort(depths.begin(), depths.end());

  auto summary = [](std::vector<double> v, const char* label) {
    std::sort(v.begin(), v.end());
    const size_t k = v.size();
    const double med = k % 2 ? v[k / 2] : 0.5 * (v[k / 2 - 1] + v[k / 2]);
    std::printf("%s median %.3f ms  min %.3f  max %.3f  (%.1f fps) over %zu frames\n", label, med, v.front(), v.back(),
                1000.0 / med, k);
  };
  std::printf("\n");
  summary(ms, "frame:   ");
  summary(solveMs, "solve:   ");
  std::printf("          (frame: end to end incl. pair upload and depth download; solve: GPU time of the graph)\n");
  std::printf("depth:    %.1f %% of pixels finite, median %.3f m\n", 100.0 * finite / double(n),
              depths.empty() ? 0.0 : double(depths[depths.size() / 2]));

  if (sequence > 0) {
    // One frame of the sequence: end to end as frame() (pair upload, next(), depth download,
    // synchronise) and its GPU time from events around next(). Returns whether it was warm.
    auto sequenceFrame = [&](double& frameMs, double& gpuMs) {
      const auto t0 = std::chrono::steady_clock::now();
      ok(cudaMemcpyAsync(dPair, hPair, 2 * n * sizeof(float), cudaMemcpyHostToDevice, stream), "upload");
      ok(cudaEventRecord(e0, stream), "cudaEventRecord");
      const cs::cuda::DeviceDepth d = stereo.next(dPair, dPair + n);
      ok(cudaEventRecord(e1, stream), "cudaEventRecord");
      ok(cudaMemcpyAsync(hDepth, d.radial, n * sizeof(float), cudaMemcpyDeviceToHost, stream), "download");
      ok(cudaStreamSynchronize(stream), "synchronize");
      frameMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      float t = 0.f;
      ok(cudaEventElapsedTime(&t, e0, e1), "cudaEventElapsedTime");
      gpuMs = t;
      return d.warm;
    };
    // Warm-up: each kind of frame run directly, recorded, replayed (a sequence restarted
    // cold three times, two frames each).
    double frameMs = 0, gpuMs = 0;
    for (int i = 0; i < 3; ++i) {
      stereo.resetSequence();
      for (int k = 0; k < 2; ++k) sequenceFrame(frameMs, gpuMs);
    }
    stereo.resetSequence();
    std::vector<double> warmMs, warmGpuMs, coldMs, coldGpuMs;
    for (int i = 0; i < sequence; ++i) {
      const bool warm = sequenceFrame(frameMs, gpuMs);
      (warm ? warmMs : coldMs).push_back(frameMs);
      (warm ? warmGpuMs : coldGpuMs).push_back(gpuMs);
    }
    std::printf(
        "\nsequence: %d frames through next() on the same pair (static camera): %zu warm, %zu cold (coldEvery %d)\n",
        sequence, warmMs.size(), coldMs.size(), params.coldEvery);
    if (!warmMs.empty()) {
      summary(warmMs, "warm:    ");
      summary(warmGpuMs, "warm GPU:");
    } else {
      std::printf("warm:     none (these parameters solve every frame cold: warmStart needs the band sweep)\n");
    }
    if (!coldMs.empty()) {
      summary(coldMs, "cold:    ");
      summary(coldGpuMs, "cold GPU:");
    }
    std::printf("          (end to end incl. pair upload and depth download; GPU: events around next())\n");
  }
  cudaFree(dPair);
  cudaFreeHost(hPair);
  cudaFreeHost(hDepth);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "error: %s\n", e.what());
  return 1;
}

// Helpers shared by the test suites.
#pragma once
#include <doctest/doctest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include "synth/scene.hpp"

namespace cs::test {

// Whether two float images hold the same bits, NaN included (equal sizes).
inline bool sameBits(const ImageF& a, const ImageF& b) {
  return a.width == b.width && a.height == b.height &&
         std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0;
}

// The message of the cs::Error that f throws, "" when it throws none.
inline std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// Path of a file in ../shared/data, or "" when the data set is not present.
inline std::string sharedData(const std::string& rel) {
  std::filesystem::path p = std::filesystem::path(CS_SHARED_DATA) / rel;
  return std::filesystem::exists(p) ? p.string() : std::string();
}

inline std::string goldenDir() { return CS_GOLDEN_DIR; }

// The mean of each factor x factor block (images), or the block's centre sample (depth and
// range: averaging would mix surfaces).
inline ImageF shrink(const ImageF& in, int factor, bool average) {
  ImageF out(in.width / factor, in.height / factor);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      if (!average) {
        out(x, y) = in(x * factor + factor / 2, y * factor + factor / 2);
        continue;
      }
      float sum = 0;
      for (int v = 0; v < factor; ++v)
        for (int u = 0; u < factor; ++u) sum += in(x * factor + u, y * factor + v);
      out(x, y) = sum / float(factor * factor);
    }
  return out;
}

// Accuracy is measured in the Release build. The sanitizer build, about ten times slower,
// runs the same code with short solves (shortUnderSanitizers) and skips the bounds.
inline bool accuracyMeasured() {
  if (CS_SANITIZED) MESSAGE("accuracy not measured in the sanitizer build (short solves)");
  return !CS_SANITIZED;
}
inline int shortUnderSanitizers(int warps) { return CS_SANITIZED ? std::min(warps, 5) : warps; }

// The folders tempDir() made, removed (with everything in them) when the test program
// ends, pass or fail, so that a test run leaves nothing in the temp folder. Set
// CURVESTEREO_KEEP_TEST_DIRS=1 to keep them for a look at a failing test's files.
class TempDirs {
 public:
  static TempDirs& instance() {
    static TempDirs dirs;
    return dirs;
  }
  void add(const std::filesystem::path& p) {
    const std::lock_guard<std::mutex> lock(mutex_);
    paths_.push_back(p);
  }
  ~TempDirs() {
    if (std::getenv("CURVESTEREO_KEEP_TEST_DIRS")) return;
    std::error_code ec;
    for (const auto& p : paths_) std::filesystem::remove_all(p, ec);
  }

 private:
  TempDirs() = default;
  std::mutex mutex_;
  std::vector<std::filesystem::path> paths_;
};

// A fresh temporary directory for one test: curvestereo_test_<pid>_<name> (the process id
// keeps concurrent runs of the suites apart), removed at the program's end (TempDirs).
inline std::filesystem::path tempDir(const std::string& name) {
  TempDirs& dirs = TempDirs::instance();  // constructed first: destroyed after every test's use
  const auto p =
      std::filesystem::temp_directory_path() / ("curvestereo_test_" + std::to_string(long(::getpid())) + "_" + name);
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  dirs.add(p);
  return p;
}

// A small synthetic fisheye pair (by default nearest surface 1.5 m, one sample per pixel):
// quick to render and to solve on every backend.
inline synth::SynthPair smallSynthPair(int size, const std::string& motion, double baseline, uint32_t seed,
                                       double nearest = 1.5, int samplesPerAxis = 1) {
  synth::SynthConfig cfg;
  cfg.camera = synth::defaultFisheye(size);
  cfg.motion = motion;
  cfg.baseline = baseline;
  cfg.seed = seed;
  cfg.nearest = nearest;
  cfg.samplesPerAxis = samplesPerAxis;
  return synth::renderPair(cfg);
}

}  // namespace cs::test

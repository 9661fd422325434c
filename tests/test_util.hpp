// Helpers shared by the test suites.
#pragma once
#include <doctest/doctest.h>

#include <cstdint>
#include <filesystem>
#include <string>

#include "synth/scene.hpp"

namespace cs::test {

// Path of a file in ../shared/data, or "" when the data set is not present.
inline std::string sharedData(const std::string& rel) {
  std::filesystem::path p = std::filesystem::path(CS_SHARED_DATA) / rel;
  return std::filesystem::exists(p) ? p.string() : std::string();
}

inline std::string goldenDir() { return CS_GOLDEN_DIR; }

// A fresh temporary directory for one test.
inline std::filesystem::path tempDir(const std::string& name) {
  auto p = std::filesystem::temp_directory_path() / ("curvestereo_test_" + name);
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
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

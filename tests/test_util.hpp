// Helpers shared by the test suites.
#pragma once
#include <doctest/doctest.h>

#include <filesystem>
#include <string>

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

}  // namespace cs::test

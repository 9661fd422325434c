// Shared by the libFuzzer targets: the image readers take paths, so each input is
// written to a per-process scratch file first (in /dev/shm when it exists).
#pragma once
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

namespace cs::fuzz {

inline const std::string& scratchPath(const char* suffix) {
  static const std::string path = [&] {
    const std::filesystem::path dir = std::filesystem::is_directory("/dev/shm")
                                          ? std::filesystem::path("/dev/shm")
                                          : std::filesystem::temp_directory_path();
    return (dir / ("curvestereo_fuzz_" + std::to_string(getpid()) + suffix)).string();
  }();
  return path;
}

inline const std::string& writeScratch(const uint8_t* data, size_t size, const char* suffix) {
  const std::string& path = scratchPath(suffix);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) __builtin_trap();
  if (size && std::fwrite(data, 1, size, f) != size) __builtin_trap();
  std::fclose(f);
  return path;
}

}  // namespace cs::fuzz

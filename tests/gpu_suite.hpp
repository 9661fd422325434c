// GPU suites (test_backends, test_backend_vulkan, test_cuda_device) run with
// gpu_test_main.cpp: a test that found its GPU backend usable calls gpuUsed(); a suite in
// which none did exits with kSkipReturnCode, which ctest reports as skipped (the test's
// SKIP_RETURN_CODE, tests/CMakeLists.txt) instead of passing.
#pragma once

namespace cs::test {

constexpr int kSkipReturnCode = 77;

inline bool& gpuUsedFlag() {
  static bool used = false;
  return used;
}
inline void gpuUsed() { gpuUsedFlag() = true; }

}  // namespace cs::test

// main() of the GPU suites (gpu_suite.hpp): doctest's, but "skipped" for ctest when no
// test found a GPU backend to run on.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstdio>

#include "gpu_suite.hpp"

int main(int argc, char** argv) {
  doctest::Context context(argc, argv);
  const int result = context.run();
  if (context.shouldExit() || result != 0) return result;
  if (!cs::test::gpuUsedFlag()) {
    std::printf("SKIPPED: no GPU backend could run here (the reasons are above)\n");
    return cs::test::kSkipReturnCode;
  }
  return result;
}

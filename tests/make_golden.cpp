// Regenerates tests/golden/ from the CPU oracle. Run it only when a change to the
// oracle is intended, and say why in the commit that updates the images:
//   build/tests/make_golden tests/golden
#include <cstdio>
#include <filesystem>

#include "curvestereo/image_io.hpp"
#include "golden_cases.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_golden GOLDEN_DIR\n");
    return 2;
  }
  try {
    const std::string dir = argv[1];
    std::filesystem::create_directories(dir);
    auto cpu = cs::createBackend("cpu");
    int written = 0;
    for (const auto& c : cs::golden::kernelCases())
      for (const auto& out : c.run(*cpu)) {
        cs::writeExr((std::filesystem::path(dir) / (out.name + ".exr")).string(), out.planes);
        ++written;
      }
    const cs::golden::SolveInputs in = cs::golden::renderSolveInputs();
    cs::golden::saveSolveInputs(in, dir);
    for (const auto& out : cs::golden::runSolve(in, "cpu")) {
      cs::writeExr((std::filesystem::path(dir) / (out.name + ".exr")).string(), out.planes);
      ++written;
    }
    std::printf("wrote %d golden images (+ solve inputs) to %s\n", written, dir.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_golden: error: %s\n", e.what());
    return 1;
  }
}

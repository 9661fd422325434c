// The CPU oracle against its stored golden images (tests/golden/, made by make_golden).
// Every kernel on odd-sized masked inputs, then a whole solve.
#include <filesystem>

#include "curvestereo/image_io.hpp"
#include "golden_cases.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

ImageF loadGolden(const std::string& name) {
  return readExr((std::filesystem::path(test::goldenDir()) / (name + ".exr")).string());
}

}  // namespace

// The oracle is compiled without floating-point contraction, so on the same compiler it
// reproduces its goldens bit for bit; the tolerance only absorbs libm differences
// (exp, pow, sqrt rounding) between C libraries.
TEST_CASE("every kernel of the CPU oracle matches its golden images") {
  auto cpu = createBackend("cpu");
  for (const auto& c : golden::kernelCases()) {
    for (const auto& out : c.run(*cpu)) {
      INFO("kernel " << c.kernel << ", output " << out.name);
      ImageF expected = loadGolden(out.name);
      REQUIRE(expected.width == out.planes.width);
      REQUIRE(expected.height == out.planes.height);
      golden::Difference d = golden::compare(out.planes, expected, 1e-5);
      MESSAGE(out.name << ": max abs " << d.maxAbs << ", NMSE " << d.nmse);
      CHECK(d.mismatchedNonFinite == 0);
      CHECK(d.maxAbs <= 1e-5);
      CHECK(d.nmse <= 1e-10);
    }
  }
}

TEST_CASE("a whole solve of the CPU oracle matches its golden disparity and warp") {
  const golden::SolveInputs in = golden::loadSolveInputs(test::goldenDir());
  for (const auto& out : golden::runSolve(in, "cpu")) {
    INFO("output " << out.name);
    ImageF expected = loadGolden(out.name);
    golden::Difference d = golden::compare(out.planes, expected, 1e-3);
    MESSAGE(out.name << ": max abs " << d.maxAbs << " px, " << 100 * d.fractionWithin() << " % within 1e-3 px");
    CHECK(d.mismatchedNonFinite == 0);
    CHECK(d.fractionWithin() >= 0.999);
    CHECK(d.maxAbs <= 0.05);
  }
}

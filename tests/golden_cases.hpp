// The golden cases: every kernel of the Backend interface on deterministic inputs of odd
// sizes with masked discs, and one whole solve. The same cases drive the oracle-vs-golden
// test and (as backends arrive) every-backend-vs-oracle tests; tests/make_golden.cpp
// regenerates tests/golden/ from the CPU oracle.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "curvestereo/backend.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/rig.hpp"

namespace cs::golden {

// Deterministic pseudo-random value in [0, 1] from an integer (an integer hash; no std
// distributions, so inputs are identical on every platform).
inline float hash01(uint32_t i) {
  i ^= i >> 16;
  i *= 0x7feb352dU;
  i ^= i >> 15;
  i *= 0x846ca68bU;
  i ^= i >> 16;
  return float(i & 0xffffff) / float(0xffffff);
}

// How far another backend's output may lie from the oracle's (test_backends): the largest
// absolute difference and the normalised mean square error. The default allows a few ulps of
// values of order 1 (fused multiply-adds, reordered sums, device exp and pow); a case whose
// outputs need another says so where it makes them, with the reason (within()).
struct Tolerance {
  double maxAbs = 1e-4, nmse = 1e-9;
};

// One output buffer of one case: channels stacked vertically (height * channels rows) so
// it fits a single-channel EXR.
struct Output {
  std::string name;  // "<kernel>_<buffer>", also the file name without .exr
  ImageF planes;
  Tolerance tolerance;
};

// The outputs, each with this tolerance.
inline std::vector<Output> within(std::vector<Output> outputs, Tolerance t) {
  for (Output& o : outputs) o.tolerance = t;
  return outputs;
}

struct KernelCase {
  std::string kernel;
  std::vector<Output> (*run)(Backend& backend);
};

// The primal-dual parameters of the kernel cases (and of the GPU suites' primal-dual
// checks): lambda 20, alpha0 17, alpha1 1.2 and `iterations` steps of the accelerated
// schedule with gamma = 0.35 (theta_k = 1 / sqrt(1 + 2 gamma scale_k), as the pipeline).
PrimalDualParams primalDualCaseParams(int iterations);

// All kernel cases, in a fixed order.
const std::vector<KernelCase>& kernelCases();

// The whole-solve case: a small rendered pair (inputs stored in the golden folder, so
// renderer changes do not move the goldens) solved with a short schedule.
struct SolveInputs {
  Rig rig;
  ImageF left, right;
};
SolveInputs renderSolveInputs();                      // used by the generator only
SolveInputs loadSolveInputs(const std::string& dir);  // from the golden folder
void saveSolveInputs(const SolveInputs& in, const std::string& dir);
std::vector<Output> runSolve(const SolveInputs& in, const std::string& backend);

// Comparison with an explicit metric: max abs error and normalised mean square error
// (sum (a-b)^2 / sum b^2) over finite reference values; non-finite values must match.
struct Difference {
  double maxAbs = 0, nmse = 0;
  long long mismatchedNonFinite = 0;
  double fractionWithin() const { return withinCount / double(std::max(1LL, count)); }
  long long withinCount = 0, count = 0;
};
Difference compare(const ImageF& actual, const ImageF& expected, double tol);

}  // namespace cs::golden

// Solver parameters, named presets, and the pyramid plan derived from them.
#pragma once
#include <string>
#include <vector>

namespace cs {

struct Params {
  // Pyramid: `levels` levels at scale 1/scale each; fewer if the coarsest width
  // would drop below `minWidth`.
  int levels = 5;
  double scale = 2.0;
  int minWidth = 50;

  // Warping (outer) and primal-dual (inner) iterations per level.
  int warps = 30;
  int iterations = 10;
  float duMax = 0.2f;        // clamp of the disparity increment per warp (px of that level)
  bool medianFilter = true;  // 3x3 median of u after each warp's iterations

  // Energy: lambda |rho| + alpha0 |grad v| + alpha1 |D grad u - v|
  float lambda = 20.f;
  float alpha0 = 17.f;
  float alpha1 = 1.2f;
  // Structure tensor D = w n n^T + n_perp n_perp^T, w = max(exp(-beta |grad I|^eta), wMin)
  float beta = 9.f;
  float eta = 0.85f;
  float wMin = 1e-4f;
  float tensorSigma = 1.0f;  // Gaussian smoothing (px) of I0 before its gradient

  // Accelerated primal-dual (Chambolle & Pock 2011, Alg. 2) with strong-convexity
  // estimate gamma; gamma = 0 gives constant steps and theta = 1.
  float gamma = 0.f;

  // Field of view used: rays farther than maxFovDeg/2 from the optical axis are masked
  // (0 = everything the camera model represents, which for an undistorted equidistant
  // model reaches into the black image corners; set it above 180 for wider lenses).
  // Pixels whose ray is closer than epipoleDeg to the baseline direction (where depth is
  // unobservable) are masked too.
  double maxFovDeg = 180.0;
  double epipoleDeg = 3.0;

  // Throws cs::Error naming the first out-of-range value.
  void validate() const;
};

// Named presets: "realtime" (the paper's configuration), "default" (accuracy oriented).
// Throws cs::Error listing the known names for an unknown one.
Params preset(const std::string& name);
std::vector<std::string> presetNames();

struct LevelSize {
  int width, height;
  double scale;  // level width / full width
};

// Level 0 first (full resolution).
std::vector<LevelSize> pyramidPlan(int width, int height, const Params& p);

// "levels=5 scale=2 warps=30 ..." for logs and bench reports.
std::string describe(const Params& p);

}  // namespace cs

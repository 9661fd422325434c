// What every evaluated method returns, and the shared conversion from a per-pixel radial
// depth of camera 0 to the 2-D warp that `evaluate` scores (docs/accuracy.md "How accuracy
// is measured": baselines are converted from depth to w the same way as ground truth).
#pragma once
#include <chrono>
#include <string>

#include "curvestereo/image.hpp"
#include "curvestereo/rig.hpp"

namespace cs::baselines {

struct MethodResult {
  FlowImage warp;  // w into the rotation-compensated image 1; NaN where there is no estimate
  ImageF depth;    // radial depth of camera 0 (metres); NaN none, +inf at infinity
  double ms = 0;   // wall time of the method (rectification and mapping back included)
};

// w(x) = pi0(depth(x) pi0^-1(x) + t') - x for every pixel of camera 0 (NaN where depth is
// NaN or the point does not project). The result's ms is left at 0.
MethodResult resultFromDepth(const Rig& rig, const ImageF& radialDepth);

// Bilinear sample of img at (x, y) (pixel centres at integers); NaN outside the image.
// Samples whose four neighbours are not all finite fall back to the nearest finite
// neighbour with positive weight (NaN if none): depth edges are not blurred across holes.
float sampleBilinear(const ImageF& img, double x, double y);

// Milliseconds since `start` (std::chrono::steady_clock).
double msSince(const std::chrono::steady_clock::time_point& start);

}  // namespace cs::baselines

// DepthResult, what cs::Stereo returns for a pair or a sequence's frame (stereo.hpp includes
// it): the valid mask, disparity, warp, depth maps, confidence and the frame's timing.
#pragma once
#include <vector>

#include "curvestereo/image.hpp"
#include "curvestereo/timing.hpp"
#include "curvestereo/triangulate.hpp"

namespace cs {

// Where valid is 1, disparity and warp are finite and depth.radial is finite and positive
// or +inf (zero disparity: a point at infinity; depth.z is +inf too). Where valid is 0,
// every output is NaN.
struct DepthResult {
  ImageU8 valid;     // 1 where the pixel was solved
  ImageF disparity;  // u: px along the epipolar curve (NaN where invalid)
  FlowImage warp;    // w: 2-D displacement into the calibrated image 1 (NaN where invalid)
  DepthMaps depth;   // radial / z depth and 3-D points
  // How far each pixel's depth can be trusted, in [0, 1] (NaN where valid is 0), for every
  // preset: the product of the structure along the epipolar curve (low on plain walls and
  // the sky), the photometric agreement the estimate leaves (low where it matched the wrong
  // thing), the plane sweep's left-right consistency (with the initialiser: low in
  // occlusions and at the rim) and, with Params::lrCheck, the final round trip's. See
  // docs/confidence.md.
  ImageF confidence;
  std::vector<StageTime> stages;  // time of each stage of this frame (when profiling)
  double totalMs = 0;
  // Sequences (Stereo::next): whether this frame started from the previous one's estimate,
  // whether it was a warm frame that failed its check and was solved again cold, and the
  // two figures a warm frame is judged by (Params::warmFailRatio; NaN for compute(), with
  // the check off, and the first without the initialiser): the share of valid pixels at the
  // sweep's level that passed its left-right check, and the mean of the confidence over the
  // field of view, which falls where the images disagree with the estimate (the data
  // residual after the last warp).
  bool warm = false;
  bool redone = false;
  double consistentShare = 0;
  double meanConfidence = 0;
  // Params::lrCheck: the share of the pixels in the field of view whose left-right round
  // trip passed (NaN without it): how much of a real pair survives the check, the figure
  // there is without ground truth.
  double lrPassShare = 0;
};

}  // namespace cs

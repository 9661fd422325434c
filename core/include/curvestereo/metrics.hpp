// The evaluation of DESIGN.md "Evaluation definitions".
#pragma once
#include "curvestereo/image.hpp"
#include "curvestereo/rig.hpp"

namespace cs {

struct Metrics {
  double tau1 = 0, tau3 = 0, epe = 0;           // all evaluated pixels; tau in percent
  double tau1Noc = 0, tau3Noc = 0, epeNoc = 0;  // non-occluded pixels
  double absRel = 0;                            // mean |d_est - d_gt| / d_gt where estimated
  double density = 0;                           // percent of evaluated pixels with an estimate
  long long evaluated = 0, nonOccluded = 0;
};

// Ground-truth warp from camera 0's radial depth. Pixels without a finite positive depth
// (sky, outside the image circle) get NaN.
FlowImage groundTruthWarp(const Rig& rig, const ImageF& depthLeft);

// Non-occluded pixels: the 3-D point projects inside camera 1's image and agrees with
// depthRight (2 % relative). Without depthRight only visibility in image 1 is checked.
ImageU8 nonOccludedMask(const Rig& rig, const ImageF& depthLeft, const ImageF* depthRight);

// est: estimated warp, NaN components where there is no estimate. estDepth: radial depth
// (NaN where none). errorMap (optional) receives |w_est - w_gt| (NaN where not evaluated,
// +inf where evaluated without an estimate).
Metrics evaluate(const Rig& rig, const FlowImage& est, const ImageF& estDepth, const ImageF& depthLeft,
                 const ImageF* depthRight, ImageF* errorMap = nullptr);

}  // namespace cs

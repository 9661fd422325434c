// The evaluation of docs/accuracy.md "How accuracy is measured".
#pragma once
#include <vector>

#include "curvestereo/image.hpp"
#include "curvestereo/pose.hpp"
#include "curvestereo/rig.hpp"

namespace cs {

struct Metrics {
  double tau1 = 0, tau3 = 0, epe = 0;           // all evaluated pixels; tau in percent
  double tau1Noc = 0, tau3Noc = 0, epeNoc = 0;  // non-occluded pixels
  double absRel = 0;                            // mean |d_est - d_gt| / d_gt where estimated
  double density = 0;                           // percent of evaluated pixels with an estimate
  // Sky: of the pixels whose true depth is +inf (inside the image circle), the percent whose
  // estimate is +inf or missing (NaN when there are none).
  double sky = 0;
  long long evaluated = 0, nonOccluded = 0, skyPixels = 0;
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

// Sparsification (docs/confidence.md): how well a confidence ranks the pixels. For each share
// kept (100, 95, ..., 50 % of the evaluated pixels: errorMap not NaN), tau>k of the most
// confident ones, the pixels without an estimate (error +inf, or a NaN confidence) ranked
// last, ties in the order of the pixels; beside it the oracle's curve, the pixels ranked by
// their true error. area: the curve's mean over the shares kept (trapezoids; in percent, like
// tau), lower is better; the oracle's is the best any ranking can do. Throws cs::Error when
// the images' sizes differ.
struct Sparsification {
  std::vector<double> keptPercent, tau, oracleTau;
  double area = 0, oracleArea = 0;
  long long evaluated = 0;
};
Sparsification sparsification(const ImageF& errorMap, const ImageF& confidence, double k);

// --- sequences (docs/accuracy.md "How accuracy is measured", sequences) ---

// tau>k in percent over the pixels where mask != 0 that errorMap (evaluate()'s) evaluates
// (not NaN); a pixel without an estimate (+inf) counts as an error. NaN when there is no
// such pixel. pixels (optional) receives their number. For the moving-object pixels of a
// sequence frame (its mover mask).
double maskedTau(const ImageF& errorMap, const ImageU8& mask, double k, long long* pixels = nullptr);

// Flicker between frames k-1 (prev) and k of a sequence: the mean of |e_k(x) - e_{k-1}(x')|
// over the static surface points seen in both frames, e = (est - gt) / gt the relative error
// of radial depth (capped at 1 as evaluate()'s absRel caps it: an estimate of more than twice
// the true depth, or +inf, counts as e = 1).
// For each pixel x of frame k with finite positive gt, an estimate (finite or +inf, > 0) and
// mover(x) == 0: the point gt(x) * ray(x) is moved into frame k-1's camera 0 (the inverse of
// prevToCurrent = motionBetween(pose_{k-1}, pose_k)) and projected with cam0; x' is the
// nearest pixel. The point counts when x' lies in the image, moverPrev(x') == 0, estPrev(x')
// is an estimate and gtPrev(x') agrees with the moved point's distance within 2 % (else the
// point is occluded in frame k-1, or off its image). Movers may be null (no moving object).
// Returns NaN when no point counts; points (optional) receives how many did. Throws
// cs::Error when the images' sizes differ from each other or from cam0's.
double flicker(const Camera& cam0, const ImageF& estPrev, const ImageF& gtPrev, const ImageF& est, const ImageF& gt,
               const ImageU8* moverPrev, const ImageU8* mover, const Motion& prevToCurrent,
               long long* points = nullptr);

}  // namespace cs

// Fisheye plane sweep (Häne et al. 2014, with spheres instead of planes): depth
// hypotheses are spheres around camera 0, uniformly spaced in inverse depth; image 1 is
// resampled through the camera models for each, scored by ZNCC over a square window
// against image 0, and the winner (winner-take-all) is refined by a parabola through its
// neighbours. Optionally the sweep is repeated from camera 1 and the two are checked for
// left-right consistency. The core works on any rig the camera models describe and runs
// multi-threaded over bands of rows; it is meant to be reused (e.g. as an initialiser).
#pragma once
#include "baselines/method.hpp"
#include "curvestereo/camera.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/rig.hpp"

namespace cs::baselines {

struct SweepParams {
  double scale = 1.0;       // working level relative to the input: 1, 1/2, 1/4 (2x2 box pyramid)
  int window = 7;           // ZNCC window side (odd, level px)
  double minDepth = 0.8;    // nearest sphere (m); hypotheses run from 1/minDepth to 0 (infinity)
  double pxPerPlane = 1.0;  // largest image motion between neighbouring hypotheses (level px)
  int planes = 0;           // number of hypotheses; 0 = from pxPerPlane and the rig
  double maxFovDeg = 180;   // rays farther than maxFovDeg/2 off camera 0's axis are not swept
  int threads = 0;          // 0 = std::thread::hardware_concurrency()
};

struct SweepResult {
  Camera cam;       // the reference camera at the working level
  ImageF invDepth;  // 1 / radial depth (1/m), sub-hypothesis refined; NaN where nothing scored
  ImageF cost;      // 1 - ZNCC of the winner (0 = perfect match, 2 = inverted)
  ImageF distinct;  // best non-adjacent other cost minus the winner's (>= 0; 0 = ambiguous)
  int planes = 0;
  double qMax = 0;  // inverse depth of the nearest hypothesis
};

// Sweep with rig.cam0 as the reference. Images at the rig's resolution, gray [0, 1].
SweepResult planeSweep(const Rig& rig, const ImageF& img0, const ImageF& img1, const SweepParams& params);

// The same rig seen from camera 1 (camera 1 becomes camera 0).
Rig swapRig(const Rig& rig);

// 1 where the depth of `ref` (reference camera 0 of rig), carried to camera 1, finds in
// `other` (swept from camera 1) a point that projects back within tolPx (level px).
ImageU8 leftRightCheck(const Rig& rig, const SweepResult& ref, const SweepResult& other, double tolPx);

// Radial depth on the full-resolution grid of `full` (bilinear in inverse depth, no
// blending across holes); pixels with mask == 0 (optional, level grid) become NaN.
ImageF upsampleDepth(const SweepResult& r, const Camera& full, const ImageU8* mask = nullptr);

// Box-filter pyramid: the image at scale 1/2^n (n = 0, 1, 2, ...).
ImageF downsample(const ImageF& img, double scale);

}  // namespace cs::baselines

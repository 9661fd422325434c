// The methods `curvestereo eval` compares (one source file each in tools/baselines/).
#pragma once
#include <string>

#include "baselines/method.hpp"
#include "baselines/planesweep.hpp"
#include "curvestereo/params.hpp"

// ---- The methods of `curvestereo eval` (one file each in tools/baselines/) ----

namespace cs::baselines {

// rectified-tgv (rectify.cpp): both images rectified to a common perspective view of
// fovDeg (size x size), our pipeline run unchanged on the pinhole rig (constant
// trajectory field, no calibration warp), mapped back to camera 0. ms: image
// resampling + solve + mapping back (the rectification maps, like our fields, are per rig).
MethodResult runRectifiedTgv(const Rig& rig, const ImageF& left, const ImageF& right, const Params& params,
                             const std::string& backend, double fovDeg, int size);

// planesweep / planesweep-valid (planesweep.cpp): `all` has every swept pixel, `valid`
// only those passing the left-right check and the distinctiveness test.
struct PlaneSweepOptions {
  SweepParams sweep;
  double lrTolPx = 1.0;       // left-right tolerance (level px)
  float minDistinct = 0.02f;  // second-best minus best cost
  float maxCost = 0.7f;       // 1 - ZNCC of the winner
};
void runPlaneSweep(const Rig& rig, const ImageF& left, const ImageF& right, const PlaneSweepOptions& options,
                   MethodResult& all, MethodResult& valid);

// opencv-sgbm (sgbm.cpp): our rectification maps (rectify.hpp) + cv::StereoSGBM.
struct SgbmOptions {
  int blockSize = 5;
  int uniquenessRatio = 10;
  int speckleWindow = 100;
  int speckleRange = 2;
  int disp12MaxDiff = 1;
  double minDepth = 0.8;  // sets numDisparities = f B / minDepth (rounded up to 16)
};
bool sgbmAvailable();
// Throws cs::Error when built without OpenCV.
MethodResult runSgbm(const Rig& rig, const ImageF& left, const ImageF& right, const SgbmOptions& options, double fovDeg,
                     int size);

}  // namespace cs::baselines

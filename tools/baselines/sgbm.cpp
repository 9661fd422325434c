// opencv-sgbm: the practitioner's pipeline (rectify to a perspective view, StereoSGBM).
// The rectification maps are ours (rectify.hpp), so only the matcher is OpenCV's; without
// OpenCV the method reports itself unavailable.
#include <chrono>
#include <cmath>
#include <limits>

#include "baselines/methods.hpp"
#include "baselines/rectify.hpp"

#ifdef CURVESTEREO_HAVE_OPENCV
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#endif

namespace cs::baselines {

#ifdef CURVESTEREO_HAVE_OPENCV

bool sgbmAvailable() { return true; }

MethodResult runSgbm(const Rig& rig, const ImageF& left, const ImageF& right, const SgbmOptions& o, double fovDeg,
                     int size) {
  const Rectification rect = makeRectification(rig, fovDeg, size);
  const auto start = std::chrono::steady_clock::now();
  ImageU8 valid0;
  const ImageF l = remap(left, rect.map0, &valid0), r = remap(right, rect.map1);
  cv::Mat L(size, size, CV_8U), Rm(size, size, CV_8U);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      L.at<uint8_t>(y, x) = uint8_t(std::lround(255.f * std::min(1.f, std::max(0.f, l(x, y)))));
      Rm.at<uint8_t>(y, x) = uint8_t(std::lround(255.f * std::min(1.f, std::max(0.f, r(x, y)))));
    }
  const double f = rect.rectified.cam0.params[0];
  const double B = rect.rectified.t.norm();
  const int numDisp = std::max(16, int(std::ceil(f * B / o.minDepth / 16.0)) * 16);
  const int bs = o.blockSize;
  // P1 / P2 as OpenCV's documentation recommends for one channel (8 and 32 times the
  // block area); 3-way mode is OpenCV's faster variant with the same energy.
  auto sgbm = cv::StereoSGBM::create(0, numDisp, bs, 8 * bs * bs, 32 * bs * bs, o.disp12MaxDiff, 0, o.uniquenessRatio,
                                     o.speckleWindow, o.speckleRange, cv::StereoSGBM::MODE_SGBM_3WAY);
  cv::Mat disp;
  sgbm->compute(L, Rm, disp);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  FlowImage w(size, size, Vec2f{nan, nan});
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const int16_t d = disp.at<int16_t>(y, x);
      if (d < 0 || !valid0(x, y)) continue;  // -16: no match
      w(x, y) = {-float(d) / 16.f, 0.f};
    }
  MethodResult res = resultFromDepth(rig, depthToSource(rect, rig.cam0, w));
  res.ms = msSince(start);
  return res;
}

#else

bool sgbmAvailable() { return false; }

MethodResult runSgbm(const Rig&, const ImageF&, const ImageF&, const SgbmOptions&, double, int) {
  throw Error(
      "opencv-sgbm is unavailable: curvestereo was built without OpenCV (install libopencv-dev and re-run cmake)");
}

#endif

}  // namespace cs::baselines

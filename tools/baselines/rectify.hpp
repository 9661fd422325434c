// Rectification of a calibrated (fisheye) rig to a common perspective view, through the
// rig's own camera models (no OpenCV), and the way back to camera 0's pixels.
//
// Both rectified cameras keep their centres and share one orientation whose x axis is
// the baseline (camera 0 -> camera 1) and whose z axis is camera 0's optical axis made
// orthogonal to it. The rectified rig is then two identical undistorted pinhole cameras,
// R = I, t = (-B, 0, 0): epipolar lines are image rows and a point at disparity d > 0
// appears d px further left in image 1.
#pragma once
#include <Eigen/Core>

#include "baselines/method.hpp"
#include "curvestereo/camera.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/rig.hpp"

namespace cs::baselines {

struct Rectification {
  Rig rectified;         // pinhole rig, R = I, t = (-B, 0, 0)
  Eigen::Matrix3d rot0;  // X_rect0 = rot0 * X_cam0
  Eigen::Matrix3d rot1;  // X_rect1 = rot1 * X_cam1
  FlowImage map0, map1;  // rectified pixel -> source pixel of camera 0 / 1 (NaN: no source)
  double fovDeg = 0;
};

// fovDeg: horizontal = vertical field of view of the square size x size rectified images
// (f = (size/2) / tan(fov/2)). Throws cs::Error for fov outside (0, 180) or a zero baseline.
Rectification makeRectification(const Rig& rig, double fovDeg, int size);

// Source pixel of camera `cam` (rotation rot: X_rect = rot X_cam) seen through rectified
// pixel p; false when the ray lies outside the camera's valid region or image.
bool rectifiedToSource(const BuiltCamera& pinhole, const BuiltCamera& cam, const Eigen::Matrix3d& rot,
                       const Vec2<double>& p, Vec2<double>& src);
// The inverse: the rectified pixel on which source pixel `src` lands; false when the ray
// points behind the rectified camera or falls outside the rectified image.
bool sourceToRectified(const BuiltCamera& pinhole, const BuiltCamera& cam, const Eigen::Matrix3d& rot,
                       const Vec2<double>& src, Vec2<double>& p);

// Bilinear resampling of img through a map (NaN entries give 0 and a 0 in `valid`).
ImageF remap(const ImageF& img, const FlowImage& map, ImageU8* valid = nullptr);

// Camera-0 radial depth from a result on the rectified rig: each pixel of camera 0 is
// carried to its rectified pixel p, the rectified warp (disparity) is sampled there
// bilinearly and re-triangulated on camera 0's exact ray. NaN outside the rectified view.
ImageF depthToSource(const Rectification& rect, const Camera& cam0, const FlowImage& rectWarp);

}  // namespace cs::baselines

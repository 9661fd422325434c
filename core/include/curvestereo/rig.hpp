// A calibrated stereo rig: two cameras and the pose of camera 1 relative to camera 0.
#pragma once
#include <Eigen/Core>
#include <string>

#include "curvestereo/camera.hpp"

namespace cs {

struct Rig {
  Camera cam0;
  Camera cam1;
  // X1 = R * X0 + t (Kalibr T_cn_cnm1 of cam1).
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  // Translation of the rotation-compensated second camera: t' = R^T t. A point X0 in
  // camera 0 is X0 + t' in a camera with cam0's orientation placed at camera 1's centre.
  Eigen::Vector3d tPrime() const { return R.transpose() * t; }
  // Throws cs::Error when the cameras are invalid, R is not a rotation or |t| ~ 0.
  void validate() const;
};

// Kalibr camchain.yaml: cam0 + cam1 with T_cn_cnm1. Models: pinhole+equidistant,
// pinhole+radtan, pinhole+none, omni+none, eucm+none, ds+none. Throws cs::Error with a
// one-line message naming the file and the problem.
Rig loadKalibr(const std::string& path);
// The same from text already in memory; `name` stands in for the path in messages.
Rig parseKalibr(const std::string& yaml, const std::string& name = "<camchain>");
void saveKalibr(const Rig& rig, const std::string& path);

}  // namespace cs

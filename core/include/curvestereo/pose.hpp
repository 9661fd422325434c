// A rigid pose and the motion between two poses of a moving rig.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace cs {

// T_world_cam0 of one frame: a point X in camera 0's frame is R X + t in the world (camera to
// world, as EuRoC's and TUM's ground truth and most odometry write it).
struct Pose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  // From a position and a unit quaternion (x, y, z, w; normalised here).
  static Pose fromQuaternion(const Eigen::Vector3d& position, double qx, double qy, double qz, double qw) {
    Pose p;
    p.R = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    p.t = position;
    return p;
  }
};

// The motion of camera 0 from the frame posed `from` to the frame posed `to`: a point X in
// `from`'s camera frame is R X + t in `to`'s (inv(T_to) T_from).
struct Motion {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
};
inline Motion motionBetween(const Pose& from, const Pose& to) {
  return {to.R.transpose() * from.R, to.R.transpose() * (from.t - to.t)};
}

}  // namespace cs

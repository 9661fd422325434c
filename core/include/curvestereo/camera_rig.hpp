// A rig of N >= 2 cameras, each with its pose in one body frame, and the stereo pairs made
// of it. The solver works on pairs (cs::Rig); CameraRig says where every camera sits, how
// much each two see of the same scene, and makes the pair Rig of any two.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "curvestereo/camera.hpp"
#include "curvestereo/fields.hpp"
#include "curvestereo/rig.hpp"

namespace cs {

// Camera-to-body: X_body = R * X_cam + p (p is the camera's centre in the body frame).
struct BodyPose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
};

struct CameraRig {
  std::vector<Camera> cameras;
  std::vector<BodyPose> poses;  // one per camera

  int size() const { return int(cameras.size()); }
  // The mean of the camera centres: the panorama's default centre.
  Eigen::Vector3d centre() const;
  // Throws one-line cs::Error naming the problem: fewer than two cameras, a camera or a
  // rotation that is invalid, two cameras at one centre (zero baseline), or a camera whose
  // view overlaps no other camera's (pairOverlap below kMinOverlap with every other).
  void validate() const;
};

// The solver's pair: camera i as cam0, camera j as cam1, X_j = R X_i + t.
Rig pairRig(const CameraRig& rig, int i, int j);
// A rectangle of an image: from pixel (x0, y0), width x height px.
struct ImageWindow {
  int x0 = 0, y0 = 0, width = 0, height = 0;
  bool empty() const { return width <= 0 || height <= 0; }
  // This window, or the whole image of `cam` where it is empty (the callers' "no window").
  ImageWindow orWhole(const Camera& cam) const { return empty() ? ImageWindow{0, 0, cam.width, cam.height} : *this; }
};
// The part of camera 0's image that a pair can solve: the bounding box of the pixels the
// fields keep (computeFields' mask: in the field of view, seen by camera 1, off the
// epipoles), found on a grid of every 4th pixel, grown by `margin` (at least 4) px and
// clamped to the image; empty when there are none. Two fisheyes 90 degrees apart share about
// half of each image, and a solve on the window costs what its pixels do (RigStereo solves
// on it).
ImageWindow solvableWindow(const Rig& pair, const FieldOptions& options, int margin);

// The rig of a pair: cam0 at the body origin.
CameraRig rigFromPair(const Rig& pair);

// The largest angle from a camera's axis that counts as its view: the image circle's when it
// lies inside the image (a lens of more than 180 degrees shows its whole circle), at least
// 90 degrees (the pair solver's default field of view), never beyond the model's range.
double viewHalfAngle(const Camera& cam);

// Which cameras of a rig have a body point (or a direction: a point at infinity) in their
// view: within viewHalfAngle of the axis and projecting into the image (occlusion aside).
class RigViews {
 public:
  explicit RigViews(const CameraRig& rig);
  bool sees(int k, const Eigen::Vector3d& bodyPoint) const;
  int seeing(const Eigen::Vector3d& bodyPoint) const;
  int seeingDirection(const Eigen::Vector3d& bodyDirection) const;

 private:
  CameraRig rig_;
  std::vector<BuiltCamera> built_;
  std::vector<double> cosHalfAngle_;
  bool seesInCamera(int k, const Eigen::Vector3d& p) const;
};

// How much camera j sees of camera i's view: the share of camera i's pixels in its view
// whose rays, at 1 m, 5 m and infinity from camera i, land in camera j's view and image
// (the mean of the three shares), sampled on a grid of at most 128 x 128 pixels (the cost
// does not grow with the resolution).
double pairOverlap(const CameraRig& rig, int i, int j);
// Below this share two cameras do not make a pair.
constexpr double kMinOverlap = 0.02;

struct PairInfo {
  int i = 0, j = 0;
  double overlapIJ = 0, overlapJI = 0;  // pairOverlap(i, j) and (j, i)
  double baseline = 0;                  // metres between the centres
};
// Every pair i < j with its overlaps and baseline.
std::vector<PairInfo> pairTable(const CameraRig& rig);
// The pairs to solve: each camera takes its `partners` best partners, ranked by overlap times
// baseline among those above kMinOverlap both ways; every camera that overlaps another is
// in a pair. The union, i < j, sorted.
std::vector<PairInfo> choosePairs(const CameraRig& rig, int partners = 2);
// "0-1,1-2": the given pairs, checked (indexes in range, i != j, no repeats, each pair above
// kMinOverlap); one-line cs::Error otherwise.
std::vector<PairInfo> parsePairs(const CameraRig& rig, const std::string& text);

// A rig calibration: a Kalibr camchain with cam0..camN-1 (the T_cn_cnm1 chain; where it is
// incomplete, every camera's T_cam_imu / T_imu_cam; the body frame is camera 0's, or the IMU's) or a Basalt
// calibration.json with N cameras (T_imu_cam; the body frame is the IMU's). The rig is
// validated. One-line cs::Error naming the file and the problem.
CameraRig loadCameraRig(const std::string& path);
CameraRig parseCameraRig(const std::string& text, const std::string& name = "<calibration>");
CameraRig parseKalibrRig(const std::string& yaml, const std::string& name = "<camchain>");
CameraRig parseBasaltRig(const std::string& json, const std::string& name = "<calibration.json>");
// Kalibr camchain of all cameras, each with T_cn_cnm1 from the one before.
void saveKalibrRig(const CameraRig& rig, const std::string& path);

}  // namespace cs

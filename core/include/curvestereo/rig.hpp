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

// ------------------------------------------------------------------------------------------
// Other calibration formats (docs/calibration.md states each convention).

enum class CalibFormat { Kalibr, Basalt, OpenCv };
// "kalibr", "basalt", "opencv".
const char* calibFormatName(CalibFormat format);

// Any supported calibration, the format chosen from the file's content: Kalibr camchain
// (cam0/cam1), Basalt calibration.json (value0.T_imu_cam ...), OpenCV FileStorage YAML or
// XML (K1 D1 K2 D2 R T). `format` (optional) receives the format read. Throws cs::Error
// with a one-line message naming the file and the problem.
Rig loadCalibration(const std::string& path, CalibFormat* format = nullptr);
Rig parseCalibration(const std::string& text, const std::string& name = "<calibration>", CalibFormat* format = nullptr);
// The format of a calibration text, from its content (throws cs::Error when none fits).
CalibFormat detectCalibFormat(const std::string& text, const std::string& name = "<calibration>");
// Writes rig in `format`; cs::Error when the format cannot represent a camera model.
void saveCalibration(const Rig& rig, const std::string& path, CalibFormat format);

// Basalt calibration.json: the first two cameras of value0.T_imu_cam / intrinsics /
// resolution. Camera types kb4, ds, eucm, ucm (as the unified model), pinhole, and
// pinhole-radtan8 whose k3..k6 are zero. The writer puts camera 0 at the IMU frame.
Rig loadBasalt(const std::string& path);
Rig parseBasalt(const std::string& json, const std::string& name = "<calibration.json>");
void saveBasalt(const Rig& rig, const std::string& path);

// OpenCV FileStorage of a stereo pair (YAML, or XML when the text starts with '<'):
// K1 D1 K2 D2 (or M1 M2), R T (X2 = R X1 + T), image_width, image_height and
// distortion_model fisheye|equidistant (Kannala-Brandt 4) or radtan|plumb_bob. Only
// those two models can be written; the writer writes XML when path ends in ".xml".
Rig loadOpenCv(const std::string& path);
Rig parseOpenCv(const std::string& text, const std::string& name = "<opencv>");
void saveOpenCv(const Rig& rig, const std::string& path);

}  // namespace cs

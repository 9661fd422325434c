// A calibrated stereo rig: two cameras and the pose of camera 1 relative to camera 0.
#pragma once
#include <Eigen/Core>
#include <functional>
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

// Kalibr camchain.yaml: cam0 + cam1 with T_cn_cnm1, or (camchain-imucam files without it)
// both cameras' T_cam_imu, giving T_cn_cnm1 = T_c1_imu T_c0_imu^-1. An OpenCV "%YAML:1.0"
// first line (OpenVINS) is allowed. Models: pinhole+equidistant, pinhole+radtan,
// pinhole+none, omni+none, omni+radtan (MEI), eucm+none, ds+none. Throws cs::Error with a
// one-line message naming the file and the problem.
Rig loadKalibr(const std::string& path);
// The same from text already in memory; `name` stands in for the path in messages.
Rig parseKalibr(const std::string& yaml, const std::string& name = "<camchain>");
void saveKalibr(const Rig& rig, const std::string& path);

// ------------------------------------------------------------------------------------------
// Other calibration formats (docs/calibration.md states each convention).

enum class CalibFormat { Kalibr, Basalt, OpenCv, OrbSlam3, VinsFusion };
// "kalibr", "basalt", "opencv", "orbslam3", "vins".
const char* calibFormatName(CalibFormat format);

// What a calibration file may leave out, supplied by the caller: the image size, which
// OpenCV's stereoCalibrate does not store (0 = not known).
struct CalibHints {
  int width = 0, height = 0;
};

// Any supported calibration, the format chosen from the file's keys (docs/calibration.md):
// Kalibr camchain (cam0/cam1), Basalt calibration.json (value0.T_imu_cam ...), OpenCV
// FileStorage YAML or XML (K1 D1 K2 D2 R T), ORB-SLAM3 settings (Camera.type ...),
// VINS-Fusion config (body_T_cam0 + cam0_calib). `format` (optional) receives the format
// read. Throws cs::Error with a one-line message naming the file, the format and the problem.
Rig loadCalibration(const std::string& path, CalibFormat* format = nullptr, const CalibHints& hints = {});
// VINS-Fusion configs name their camera files: they are read relative to `name`'s folder.
Rig parseCalibration(const std::string& text, const std::string& name = "<calibration>", CalibFormat* format = nullptr,
                     const CalibHints& hints = {});
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
// Matrices may also be plain lists ([a, b, c], cv::Vec3d / Vec4d). Without an image size
// in the file, hints' is used.
Rig loadOpenCv(const std::string& path, const CalibHints& hints = {});
Rig parseOpenCv(const std::string& text, const std::string& name = "<opencv>", const CalibHints& hints = {});
void saveOpenCv(const Rig& rig, const std::string& path);

// ORB-SLAM3 settings (OpenCV FileStorage YAML): Camera.type PinHole | KannalaBrandt8,
// File.version "1.0" keys Camera1.fx .. Camera2.k4 + Stereo.T_c1_c2 (X_c1 = T X_c2), or the
// older Camera.fx .. + Camera2.fx .. + Tlr (X_left = Tlr X_right). The writer writes 1.0.
Rig loadOrbSlam3(const std::string& path);
Rig parseOrbSlam3(const std::string& text, const std::string& name = "<orbslam3>");
void saveOrbSlam3(const Rig& rig, const std::string& path);

// VINS-Fusion config: body_T_cam0 / body_T_cam1 (X_body = T X_cam) and cam0_calib /
// cam1_calib, camodocal camera files (model_type KANNALA_BRANDT, MEI, PINHOLE) that
// `readFile` returns the text of (given the name as written in the config). The writer
// writes PATH and, beside it, <stem>_cam0.yaml and <stem>_cam1.yaml.
using FileReader = std::function<std::string(const std::string& file)>;
Rig loadVinsFusion(const std::string& path);
Rig parseVinsFusion(const std::string& text, const std::string& name, const FileReader& readFile);
void saveVinsFusion(const Rig& rig, const std::string& path);
// One camodocal camera file (image size included).
Camera parseCamodocal(const std::string& text, const std::string& name = "<camodocal>");

}  // namespace cs

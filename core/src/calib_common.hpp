// Pieces the calibration readers and writers share (Kalibr, Basalt, OpenCV): exact number
// text, one-line errors that name the file, and a YAML/JSON document with typed lookups.
// Private to core/src.
#pragma once
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

#include "curvestereo/camera_rig.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/rig.hpp"

namespace cs::calib {

std::string formatNumber(double v, int precision = 6);
// Shortest decimal text that reads back as exactly v (at most 17 significant digits), so
// a written calibration reads back bit for bit.
std::string exactNumber(double v);
// "[a, b, c]" with exactNumber.
std::string numberList(const std::vector<double>& v);
// Messages are one line; text quoted into them may not be.
std::string oneLine(std::string text);

// The whole file; throws "<path>: cannot open file (...)".
std::string readTextFile(const std::string& path);
// Writes text to path; throws "<path>: cannot open file for writing" / "error while writing".
void writeTextFile(const std::string& path, const std::string& text);

// The checks Rig::validate runs on the pose, with the pose named as the file names it
// ("T_cn_cnm1", "R, T", "T_imu_cam"). Throws cs::Error(problem) without a file name.
void checkPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const std::string& poseName);
// Camera::validate with the camera's name in front ("cam0: ...").
void checkCamera(const Camera& cam, const std::string& name);
// Both cameras and the pose; a failure becomes "<file>: <problem>".
void checkRig(Rig& rig, const std::string& file, const std::string& poseName);
// CameraRig::validate; a failure becomes "<file>: <problem>".
void checkCameraRig(const CameraRig& rig, const std::string& file);
// Throws "<path>: not saving an invalid rig: ..." for a rig a reader would refuse.
void checkRigBeforeSaving(const Rig& rig, const std::string& path);

// First non-blank character (after a UTF-8 byte-order mark), or 0 for blank text.
char firstSignificantChar(const std::string& text);

// A YAML (or JSON) document being read: typed lookups that fail with one line
// "<name>: <problem>" naming the dotted key and, where known, the line.
class YamlDoc {
 public:
  explicit YamlDoc(std::string name) : name_(std::move(name)) {}

  const std::string& name() const { return name_; }
  [[noreturn]] void fail(const std::string& problem) const;

  // Parses text; `syntax` ("YAML", "JSON") names the language in syntax errors. JSON
  // text has its tabs turned into spaces first (tabs are JSON whitespace but not YAML
  // indentation), and an OpenCV "%YAML:1.0" first line is made a comment.
  YAML::Node parse(const std::string& text, const char* syntax) const;

  static std::string lineOf(const YAML::Node& node);
  // parent[key]; fails with the dotted name ("cam1.T_cn_cnm1") when it is missing.
  YAML::Node require(const YAML::Node& parent, const std::string& key, const std::string& prefix) const;
  // parent[key] or an undefined node, without inserting anything.
  static YAML::Node find(const YAML::Node& parent, const std::string& key);
  double number(const YAML::Node& node, const std::string& key) const;
  std::vector<double> numbers(const YAML::Node& node, const std::string& key) const;
  std::string text(const YAML::Node& node, const std::string& key) const;
  // A whole number in [lo, hi].
  int integer(const YAML::Node& node, const std::string& key, int lo, int hi) const;
  // A rigid transform written by OpenCV: an !!opencv-matrix (rows, cols, data) or a plain
  // list, 4x4 or 3x4 (the last row [0 0 0 1] implied). The rotation is checked later.
  Eigen::Matrix4d transform(const YAML::Node& node, const std::string& key) const;

 private:
  std::string name_;
};

// The inverse [R^T, -R^T t] of a rigid transform.
Eigen::Matrix4d rigidInverse(const Eigen::Matrix4d& T);

// v is a whole number in [lo, hi] (checked before any cast to int, which would be
// undefined for values out of range).
inline bool wholeInRange(double v, double lo, double hi) { return v >= lo && v <= hi && v == std::floor(v); }

// "prefix.key" or "key" when prefix is empty.
inline std::string dotted(const std::string& prefix, const std::string& key) {
  return prefix.empty() ? key : prefix + "." + key;
}

}  // namespace cs::calib

// loadCalibration / saveCalibration: the format of a calibration file from its content.
#include <yaml-cpp/yaml.h>

#include <string>

#include "calib_common.hpp"
#include "curvestereo/rig.hpp"

namespace cs {

namespace {

// Names every format, so the message fits whichever the user meant.
const char* kNotACalibration =
    "not a Kalibr camchain, Basalt calibration.json or OpenCV FileStorage stereo file (expected the keys cam0 and "
    "cam1, value0.T_imu_cam / intrinsics / resolution, or K1 D1 K2 D2 R T)";

bool hasAny(const YAML::Node& map, std::initializer_list<const char*> keys) {
  for (const char* key : keys)
    if (calib::YamlDoc::find(map, key).IsDefined()) return true;
  return false;
}

}  // namespace

const char* calibFormatName(CalibFormat format) {
  switch (format) {
    case CalibFormat::Kalibr:
      return "kalibr";
    case CalibFormat::Basalt:
      return "basalt";
    case CalibFormat::OpenCv:
      return "opencv";
  }
  return "unknown";
}

// XML is OpenCV's; "%YAML:1.0" is how OpenCV starts its YAML. Otherwise the top-level
// keys decide, so a Basalt file written as YAML or an OpenCV file without the header
// are recognised too.
CalibFormat detectCalibFormat(const std::string& text, const std::string& name) {
  const char first = calib::firstSignificantChar(text);
  if (first == 0) throw Error(calib::oneLine(name + ": the file is empty"));
  if (first == '<') return CalibFormat::OpenCv;
  if (text.compare(0, 6, "%YAML:") == 0) return CalibFormat::OpenCv;
  const calib::YamlDoc doc(name);
  const YAML::Node root = doc.parse(text, first == '{' ? "JSON" : "YAML");
  if (!root.IsMap()) doc.fail(kNotACalibration);
  if (hasAny(root, {"cam0", "cam1"})) return CalibFormat::Kalibr;
  if (hasAny(root, {"value0", "T_imu_cam"})) return CalibFormat::Basalt;
  if (hasAny(root, {"K1", "M1", "D1", "K2", "M2", "D2", "R", "T"})) return CalibFormat::OpenCv;
  doc.fail(kNotACalibration);
}

Rig parseCalibration(const std::string& text, const std::string& name, CalibFormat* format) {
  const CalibFormat f = detectCalibFormat(text, name);
  if (format) *format = f;
  switch (f) {
    case CalibFormat::Kalibr:
      return parseKalibr(text, name);
    case CalibFormat::Basalt:
      return parseBasalt(text, name);
    case CalibFormat::OpenCv:
      return parseOpenCv(text, name);
  }
  throw Error(name + ": unknown calibration format");
}

Rig loadCalibration(const std::string& path, CalibFormat* format) {
  return parseCalibration(calib::readTextFile(path), path, format);
}

void saveCalibration(const Rig& rig, const std::string& path, CalibFormat format) {
  switch (format) {
    case CalibFormat::Kalibr:
      return saveKalibr(rig, path);
    case CalibFormat::Basalt:
      return saveBasalt(rig, path);
    case CalibFormat::OpenCv:
      return saveOpenCv(rig, path);
  }
  throw Error(path + ": unknown calibration format");
}

}  // namespace cs

// loadCalibration / saveCalibration: the format of a calibration file from its keys.
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <string>

#include "calib_common.hpp"
#include "curvestereo/rig.hpp"

namespace cs {

namespace {

// Names every format, so the message fits whichever the user meant.
const char* kNotACalibration =
    "not a Kalibr camchain, Basalt calibration.json, OpenCV stereo file, ORB-SLAM3 settings or VINS-Fusion config "
    "(expected the keys cam0 and cam1, value0.T_imu_cam, K1 D1 K2 D2 R T, Camera.type or Camera1.fx, or "
    "body_T_cam0 and cam0_calib)";

bool hasAny(const YAML::Node& map, std::initializer_list<const char*> keys) {
  for (const char* key : keys)
    if (calib::YamlDoc::find(map, key).IsDefined()) return true;
  return false;
}

// What the messages call each format.
const char* formatTitle(CalibFormat format) {
  switch (format) {
    case CalibFormat::Kalibr:
      return "Kalibr camchain";
    case CalibFormat::Basalt:
      return "Basalt calibration";
    case CalibFormat::OpenCv:
      return "OpenCV stereo calibration";
    case CalibFormat::OrbSlam3:
      return "ORB-SLAM3 settings";
    case CalibFormat::VinsFusion:
      return "VINS-Fusion config";
  }
  return "calibration";
}

// A VINS-Fusion config's camera files, relative to the config's folder.
FileReader siblingReader(const std::string& configPath) {
  const std::filesystem::path dir = std::filesystem::path(configPath).parent_path();
  return [dir](const std::string& file) { return calib::readTextFile((dir / file).string()); };
}

Rig parseAs(CalibFormat f, const std::string& text, const std::string& name, const CalibHints& hints) {
  switch (f) {
    case CalibFormat::Kalibr:
      return parseKalibr(text, name);
    case CalibFormat::Basalt:
      return parseBasalt(text, name);
    case CalibFormat::OpenCv:
      return parseOpenCv(text, name, hints);
    case CalibFormat::OrbSlam3:
      return parseOrbSlam3(text, name);
    case CalibFormat::VinsFusion:
      return parseVinsFusion(text, name, siblingReader(name));
  }
  throw Error(name + ": unknown calibration format");
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
    case CalibFormat::OrbSlam3:
      return "orbslam3";
    case CalibFormat::VinsFusion:
      return "vins";
  }
  return "unknown";
}

// XML is OpenCV's. Otherwise the top-level keys decide, whatever the first line says:
// OpenVINS starts its Kalibr camchains with OpenCV's "%YAML:1.0", ORB-SLAM3 and VINS-Fusion
// their settings too, and a Basalt file may be written as YAML.
CalibFormat detectCalibFormat(const std::string& text, const std::string& name) {
  const char first = calib::firstSignificantChar(text);
  if (first == 0) throw Error(calib::oneLine(name + ": the file is empty"));
  if (first == '<') return CalibFormat::OpenCv;
  const calib::YamlDoc doc(name);
  const YAML::Node root = doc.parse(text, first == '{' ? "JSON" : "YAML");
  if (!root.IsMap()) doc.fail(kNotACalibration);
  if (hasAny(root, {"cam0", "cam1"})) return CalibFormat::Kalibr;
  if (hasAny(root, {"value0", "T_imu_cam"})) return CalibFormat::Basalt;
  if (hasAny(root, {"Camera.type", "Camera1.fx", "Camera.fx", "File.version", "Stereo.T_c1_c2", "Tlr"}))
    return CalibFormat::OrbSlam3;
  if (hasAny(root, {"body_T_cam0", "body_T_cam1", "cam0_calib", "cam1_calib"})) return CalibFormat::VinsFusion;
  if (hasAny(root, {"K1", "M1", "D1", "K2", "M2", "D2", "R", "T"})) return CalibFormat::OpenCv;
  doc.fail(kNotACalibration);
}

// A reader's "<name>: <problem>" becomes "<name>: <format>: <problem>", so every refusal
// says which format the file was taken for.
Rig parseCalibration(const std::string& text, const std::string& name, CalibFormat* format, const CalibHints& hints) {
  const CalibFormat f = detectCalibFormat(text, name);
  if (format) *format = f;
  try {
    return parseAs(f, text, name, hints);
  } catch (const Error& e) {
    const std::string message = e.what(), prefix = name + ": ", title = formatTitle(f);
    if (message.compare(0, prefix.size(), prefix) != 0 || message.find(title) != std::string::npos) throw;
    throw Error(prefix + title + ": " + message.substr(prefix.size()));
  }
}

Rig loadCalibration(const std::string& path, CalibFormat* format, const CalibHints& hints) {
  return parseCalibration(calib::readTextFile(path), path, format, hints);
}

void saveCalibration(const Rig& rig, const std::string& path, CalibFormat format) {
  switch (format) {
    case CalibFormat::Kalibr:
      return saveKalibr(rig, path);
    case CalibFormat::Basalt:
      return saveBasalt(rig, path);
    case CalibFormat::OpenCv:
      return saveOpenCv(rig, path);
    case CalibFormat::OrbSlam3:
      return saveOrbSlam3(rig, path);
    case CalibFormat::VinsFusion:
      return saveVinsFusion(rig, path);
  }
  throw Error(path + ": unknown calibration format");
}

}  // namespace cs

// VINS-Fusion configs and the camodocal camera files they name, written from VINS-Fusion's
// config keys (body_T_cam0/1: the camera's pose in the body frame, X_body = T X_cam;
// cam0_calib / cam1_calib) and camodocal's camera parameter names: KANNALA_BRANDT (k2..k5,
// mu mv u0 v0: theta_d = theta + k2 theta^3 + ... + k5 theta^9), MEI (mirror xi, k1 k2 p1 p2,
// gamma1 gamma2 u0 v0) and PINHOLE (k1 k2 p1 p2, fx fy cx cy).
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "calib_common.hpp"
#include "curvestereo/rig.hpp"

namespace cs {

namespace {

using calib::exactNumber;
using calib::YamlDoc;

// One camodocal model: its model_type, and where each Camera parameter lives.
struct CamodocalModel {
  const char* type;
  CameraModel model;
  std::vector<std::pair<const char*, const char*>> params;  // (section, key) in Camera order
};

const std::vector<CamodocalModel>& camodocalModels() {
  static const std::vector<CamodocalModel> models = {
      {"KANNALA_BRANDT",
       CameraModel::KannalaBrandt4,
       {{"projection_parameters", "mu"},
        {"projection_parameters", "mv"},
        {"projection_parameters", "u0"},
        {"projection_parameters", "v0"},
        {"projection_parameters", "k2"},
        {"projection_parameters", "k3"},
        {"projection_parameters", "k4"},
        {"projection_parameters", "k5"}}},
      {"MEI",
       CameraModel::Mei,
       {{"projection_parameters", "gamma1"},
        {"projection_parameters", "gamma2"},
        {"projection_parameters", "u0"},
        {"projection_parameters", "v0"},
        {"mirror_parameters", "xi"},
        {"distortion_parameters", "k1"},
        {"distortion_parameters", "k2"},
        {"distortion_parameters", "p1"},
        {"distortion_parameters", "p2"}}},
      {"PINHOLE",
       CameraModel::PinholeRadtan,
       {{"projection_parameters", "fx"},
        {"projection_parameters", "fy"},
        {"projection_parameters", "cx"},
        {"projection_parameters", "cy"},
        {"distortion_parameters", "k1"},
        {"distortion_parameters", "k2"},
        {"distortion_parameters", "p1"},
        {"distortion_parameters", "p2"}}},
  };
  return models;
}

Camera readCamodocal(const YamlDoc& doc, const std::string& text) {
  const YAML::Node root = doc.parse(text, "YAML");
  if (!root.IsMap()) doc.fail("not a camodocal camera file (expected model_type, image_width, image_height)");
  const YAML::Node typeNode = doc.require(root, "model_type", "");
  const std::string type = doc.text(typeNode, "model_type");
  const CamodocalModel* model = nullptr;
  for (const CamodocalModel& m : camodocalModels())
    if (type == m.type) model = &m;
  if (!model)
    doc.fail("model_type '" + type + "' is not supported (KANNALA_BRANDT, MEI or PINHOLE)" + YamlDoc::lineOf(typeNode));
  Camera cam;
  cam.model = model->model;
  cam.width = doc.integer(doc.require(root, "image_width", ""), "image_width", 1, 1000000);
  cam.height = doc.integer(doc.require(root, "image_height", ""), "image_height", 1, 1000000);
  for (const auto& [section, key] : model->params) {
    const YAML::Node parent = doc.require(root, section, "");
    cam.params.push_back(doc.number(doc.require(parent, key, section), calib::dotted(section, key)));
  }
  return cam;
}

class VinsReader {
 public:
  VinsReader(std::string name, const FileReader& readFile) : doc_(std::move(name)), readFile_(readFile) {}

  Rig read(const std::string& text) const {
    const YAML::Node root = doc_.parse(text, "YAML");
    if (!root.IsMap())
      doc_.fail("not a VINS-Fusion config (expected body_T_cam0, body_T_cam1, cam0_calib, cam1_calib)");
    const YAML::Node count = YamlDoc::find(root, "num_of_cam");
    if (count.IsDefined() && doc_.number(count, "num_of_cam") != 2)
      doc_.fail("num_of_cam is " + count.Scalar() + ": a stereo rig needs 2 cameras");
    Rig rig;
    rig.cam0 = camera(root, 0);
    rig.cam1 = camera(root, 1);
    const Eigen::Matrix4d bodyCam0 = doc_.transform(doc_.require(root, "body_T_cam0", ""), "body_T_cam0");
    const Eigen::Matrix4d bodyCam1 = doc_.transform(doc_.require(root, "body_T_cam1", ""), "body_T_cam1");
    const Eigen::Matrix4d T = calib::rigidInverse(bodyCam1) * bodyCam0;  // X_cam1 = T X_cam0
    rig.R = T.topLeftCorner<3, 3>();
    rig.t = T.topRightCorner<3, 1>();
    calib::checkRig(rig, doc_.name(), "body_T_cam1^-1 body_T_cam0");
    return rig;
  }

 private:
  YamlDoc doc_;
  const FileReader& readFile_;

  Camera camera(const YAML::Node& root, int i) const {
    const std::string key = "cam" + std::to_string(i) + "_calib";
    const std::string file = doc_.text(doc_.require(root, key, ""), key);
    std::string text;
    try {
      text = readFile_(file);
    } catch (const Error& e) {
      doc_.fail(key + " '" + file + "': " + e.what());
    }
    try {
      return readCamodocal(YamlDoc(file), text);
    } catch (const Error& e) {
      doc_.fail(key + ": " + e.what());
    }
  }
};

// ------------------------------------------------------------------------------------------
// Writing: the config and two camodocal files beside it.

// Unified is MEI without distortion; the other models have no camodocal form.
const CamodocalModel& camodocalFor(const Camera& cam, const std::string& path) {
  const CameraModel model = cam.model == CameraModel::Unified ? CameraModel::Mei : cam.model;
  for (const CamodocalModel& m : camodocalModels())
    if (m.model == model) return m;
  throw Error(path + ": VINS-Fusion (camodocal) cannot represent the " + cam.modelName() +
              " camera model (only KANNALA_BRANDT, MEI and PINHOLE): write Kalibr or Basalt instead");
}

std::string camodocalText(const Camera& cam, const CamodocalModel& m, const std::string& name) {
  std::vector<double> p = cam.params;
  if (cam.model == CameraModel::Unified) p.insert(p.end(), 4, 0.0);
  std::ostringstream os;
  os << "%YAML:1.0\n---\nmodel_type: " << m.type << "\ncamera_name: " << name << "\nimage_width: " << cam.width
     << "\nimage_height: " << cam.height << "\n";
  std::string section;
  for (size_t i = 0; i < m.params.size(); ++i) {
    if (m.params[i].first != section) os << (section = m.params[i].first) << ":\n";
    os << "   " << m.params[i].second << ": " << exactNumber(p[i]) << "\n";
  }
  return os.str();
}

void writeMatrix(std::ostream& os, const char* key, const Eigen::Matrix4d& T) {
  os << key << ": !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d\n   data: [";
  for (int i = 0; i < 16; ++i) os << (i ? ", " : " ") << exactNumber(T(i / 4, i % 4));
  os << " ]\n";
}

}  // namespace

Camera parseCamodocal(const std::string& text, const std::string& name) { return readCamodocal(YamlDoc(name), text); }

Rig parseVinsFusion(const std::string& text, const std::string& name, const FileReader& readFile) {
  return VinsReader(name, readFile).read(text);
}

Rig loadVinsFusion(const std::string& path) {
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  const FileReader sibling = [dir](const std::string& file) { return calib::readTextFile((dir / file).string()); };
  return parseVinsFusion(calib::readTextFile(path), path, sibling);
}

// Camera 0 is the body frame: body_T_cam0 = I, body_T_cam1 = T_cn_cnm1^-1.
void saveVinsFusion(const Rig& rig, const std::string& path) {
  calib::checkRigBeforeSaving(rig, path);
  const CamodocalModel& m0 = camodocalFor(rig.cam0, path);
  const CamodocalModel& m1 = camodocalFor(rig.cam1, path);
  const std::filesystem::path p(path);
  const std::string stem = p.stem().string();
  const std::string file0 = stem + "_cam0.yaml", file1 = stem + "_cam1.yaml";
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = rig.R;
  T.topRightCorner<3, 1>() = rig.t;
  std::ostringstream os;
  os << "%YAML:1.0\n# VINS-Fusion config written by curvestereo (cameras and their poses only; camera 0 is the "
        "body frame).\nnum_of_cam: 2\n"
     << "cam0_calib: \"" << file0 << "\"\ncam1_calib: \"" << file1 << "\"\n"
     << "image_width: " << rig.cam0.width << "\nimage_height: " << rig.cam0.height << "\n";
  writeMatrix(os, "body_T_cam0", Eigen::Matrix4d::Identity());
  writeMatrix(os, "body_T_cam1", calib::rigidInverse(T));
  calib::writeTextFile((p.parent_path() / file0).string(), camodocalText(rig.cam0, m0, "cam0"));
  calib::writeTextFile((p.parent_path() / file1).string(), camodocalText(rig.cam1, m1, "cam1"));
  calib::writeTextFile(path, os.str());
}

}  // namespace cs

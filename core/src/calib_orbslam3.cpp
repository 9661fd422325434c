// ORB-SLAM3 settings files (OpenCV FileStorage YAML), written from ORB-SLAM3's documented
// settings keys: Camera.type PinHole (k1 k2 p1 p2) or KannalaBrandt8 (k1..k4); File.version
// "1.0" files name the cameras Camera1 / Camera2 and hold Stereo.T_c1_c2, older ones
// Camera / Camera2 and Tlr. Both transforms map the right camera's coordinates to the left
// camera's (X_c1 = T X_c2), the inverse of Kalibr's T_cn_cnm1.
#include <yaml-cpp/yaml.h>

#include <sstream>
#include <string>
#include <vector>

#include "calib_common.hpp"
#include "curvestereo/rig.hpp"

namespace cs {

namespace {

using calib::exactNumber;
using calib::YamlDoc;

class OrbSlam3Reader {
 public:
  explicit OrbSlam3Reader(std::string name) : doc_(std::move(name)) {}

  Rig read(const std::string& text) const {
    root_ = doc_.parse(text, "YAML");
    if (!root_.IsMap()) doc_.fail("not ORB-SLAM3 settings (expected a mapping with Camera.type and Camera1.fx)");
    const bool v1 = YamlDoc::find(root_, "File.version").IsDefined();
    const std::string first = v1 ? "Camera1" : "Camera", second = "Camera2";
    const CameraModel model = cameraModel();
    const int width = doc_.integer(doc_.require(root_, "Camera.width", ""), "Camera.width", 1, 1000000);
    const int height = doc_.integer(doc_.require(root_, "Camera.height", ""), "Camera.height", 1, 1000000);
    if (!YamlDoc::find(root_, second + ".fx").IsDefined())
      doc_.fail("missing key \"" + second +
                ".fx\" (a stereo rig needs both cameras' intrinsics; a rectified setup with Stereo.b or Camera.bf "
                "describes rectified images, not the lenses)");
    Rig rig;
    rig.cam0 = camera(first, model, width, height);
    rig.cam1 = camera(second, model, width, height);
    const std::string poseKey = v1 ? "Stereo.T_c1_c2" : "Tlr";
    const Eigen::Matrix4d T =
        calib::rigidInverse(doc_.transform(doc_.require(root_, poseKey, ""), poseKey));  // X_c2 = T^-1 X_c1
    rig.R = T.topLeftCorner<3, 3>();
    rig.t = T.topRightCorner<3, 1>();
    calib::checkRig(rig, doc_.name(), poseKey);
    return rig;
  }

 private:
  YamlDoc doc_;
  mutable YAML::Node root_;

  // ORB-SLAM2 files have no Camera.type: they are pinhole.
  CameraModel cameraModel() const {
    const YAML::Node node = YamlDoc::find(root_, "Camera.type");
    if (!node.IsDefined()) return CameraModel::PinholeRadtan;
    const std::string type = doc_.text(node, "Camera.type");
    if (type == "PinHole") return CameraModel::PinholeRadtan;
    if (type == "KannalaBrandt8") return CameraModel::KannalaBrandt4;
    doc_.fail("Camera.type '" + type + "' is not supported (PinHole or KannalaBrandt8)" + YamlDoc::lineOf(node));
  }

  double value(const std::string& key) const { return doc_.number(doc_.require(root_, key, ""), key); }
  double optional(const std::string& key) const {
    const YAML::Node node = YamlDoc::find(root_, key);
    return node.IsDefined() ? doc_.number(node, key) : 0.0;
  }

  Camera camera(const std::string& prefix, CameraModel model, int width, int height) const {
    Camera cam;
    cam.model = model;
    cam.width = width;
    cam.height = height;
    for (const char* p : {"fx", "fy", "cx", "cy"}) cam.params.push_back(value(prefix + "." + p));
    const bool kb = model == CameraModel::KannalaBrandt4;
    const std::vector<const char*> names =
        kb ? std::vector<const char*>{"k1", "k2", "k3", "k4"} : std::vector<const char*>{"k1", "k2", "p1", "p2"};
    // Pinhole distortion is optional (rectified or distortion-free cameras); KB's is not.
    for (const char* p : names) cam.params.push_back(kb ? value(prefix + "." + p) : optional(prefix + "." + p));
    if (!kb && optional(prefix + ".k3") != 0)
      doc_.fail(prefix + ".k3 = " + calib::formatNumber(optional(prefix + ".k3")) +
                " is not zero: only k1 k2 p1 p2 of the pinhole distortion are supported");
    return cam;
  }
};

// ------------------------------------------------------------------------------------------
// Writing (File.version 1.0).

const char* typeFor(const Rig& rig, const std::string& path) {
  for (const Camera* cam : {&rig.cam0, &rig.cam1})
    if (cam->model != CameraModel::KannalaBrandt4 && cam->model != CameraModel::PinholeRadtan)
      throw Error(path + ": ORB-SLAM3 settings cannot represent the " + cam->modelName() +
                  " camera model (only KannalaBrandt8 = Kannala-Brandt 4 and PinHole radtan): write Kalibr instead");
  if (rig.cam0.model != rig.cam1.model)
    throw Error(path + ": ORB-SLAM3 settings have one Camera.type for both cameras, but cam0 is " +
                rig.cam0.modelName() + " and cam1 " + rig.cam1.modelName());
  if (rig.cam0.width != rig.cam1.width || rig.cam0.height != rig.cam1.height)
    throw Error(path + ": ORB-SLAM3 settings have one image size, but the cameras differ in resolution");
  return rig.cam0.model == CameraModel::KannalaBrandt4 ? "KannalaBrandt8" : "PinHole";
}

void writeCamera(std::ostream& os, const Camera& cam, const std::string& prefix) {
  const bool kb = cam.model == CameraModel::KannalaBrandt4;
  const char* names[] = {"fx", "fy", "cx", "cy", "k1", "k2", kb ? "k3" : "p1", kb ? "k4" : "p2"};
  for (size_t i = 0; i < 8; ++i) os << prefix << "." << names[i] << ": " << exactNumber(cam.params[i]) << "\n";
  os << "\n";
}

}  // namespace

Rig parseOrbSlam3(const std::string& text, const std::string& name) { return OrbSlam3Reader(name).read(text); }

Rig loadOrbSlam3(const std::string& path) { return OrbSlam3Reader(path).read(calib::readTextFile(path)); }

void saveOrbSlam3(const Rig& rig, const std::string& path) {
  calib::checkRigBeforeSaving(rig, path);
  const char* type = typeFor(rig, path);
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = rig.R;
  T.topRightCorner<3, 1>() = rig.t;
  const Eigen::Matrix4d Tc1c2 = calib::rigidInverse(T);
  std::ostringstream os;
  os << "%YAML:1.0\n---\n# ORB-SLAM3 settings written by curvestereo (cameras and stereo pose only).\n"
     << "File.version: \"1.0\"\n\nCamera.type: \"" << type << "\"\n\n";
  writeCamera(os, rig.cam0, "Camera1");
  writeCamera(os, rig.cam1, "Camera2");
  os << "Camera.width: " << rig.cam0.width << "\nCamera.height: " << rig.cam0.height << "\n\n"
     << "# X_c1 = T_c1_c2 X_c2\nStereo.T_c1_c2: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d\n   data: [";
  for (int i = 0; i < 16; ++i) os << (i ? ", " : " ") << exactNumber(Tc1c2(i / 4, i % 4));
  os << " ]\n";
  calib::writeTextFile(path, os.str());
}

}  // namespace cs

// Rig validation and Kalibr camchain.yaml I/O (Basalt: calib_basalt.cpp, OpenCV: calib_opencv.cpp).
#include "curvestereo/rig.hpp"

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "calib_common.hpp"
#include "curvestereo/camera_models.hpp"
#include "curvestereo/camera_rig.hpp"
#include "curvestereo/image.hpp"

namespace cs {

using calib::exactNumber;
using calib::formatNumber;
using calib::numberList;

void Rig::validate() const {
  calib::checkCamera(cam0, "cam0");
  calib::checkCamera(cam1, "cam1");
  calib::checkPose(R, t, "T_cn_cnm1");
}

// ------------------------------------------------------------------------------------------
// Reading. Every failure is one line "<path>: <problem>".

namespace {

using calib::YamlDoc;

class KalibrReader {
 public:
  explicit KalibrReader(std::string name) : doc_(std::move(name)) {}

  Rig read(const std::string& text) const {
    const YAML::Node root = doc_.parse(text, "YAML");
    if (!root.IsMap()) fail("not a Kalibr camchain (expected a mapping with keys cam0 and cam1)");
    Rig rig;
    rig.cam0 = readCamera(root, "cam0");
    rig.cam1 = readCamera(root, "cam1");
    const std::string poseName = stereoPose(root, rig);
    calib::checkRig(rig, doc_.name(), poseName);
    return rig;
  }

  // cam0..camN-1, posed in camera 0's frame through the T_cn_cnm1 chain, or in the IMU's
  // frame when the chain is incomplete and every camera has T_cam_imu (or T_imu_cam).
  CameraRig readRig(const std::string& text) const {
    const YAML::Node root = doc_.parse(text, "YAML");
    if (!root.IsMap()) fail("not a Kalibr camchain (expected a mapping with keys cam0, cam1, ...)");
    const int n = cameraCount(root);
    CameraRig rig;
    for (int k = 0; k < n; ++k) rig.cameras.push_back(readCamera(root, cameraName(k)));
    const bool imuOnly =
        !allHave(root, n, "T_cn_cnm1", 1) && (allHave(root, n, "T_cam_imu", 0) || allHave(root, n, "T_imu_cam", 0));
    rig.poses = imuOnly ? imuPoses(root, n) : chainPoses(root, n);
    return rig;
  }

 private:
  static std::string cameraName(int k) { return "cam" + std::to_string(k); }

  // The keys camK must be cam0, cam1, ... without a gap.
  int cameraCount(const YAML::Node& root) const {
    int n = 0;
    while (YamlDoc::find(root, cameraName(n)).IsDefined()) ++n;
    for (const auto& entry : root) {
      const std::string key = entry.first.as<std::string>("");
      if (key.rfind("cam", 0) != 0 || key.size() < 4 || key.find_first_not_of("0123456789", 3) != std::string::npos)
        continue;
      if (std::stol(key.substr(3, 9)) >= n)
        fail("has " + key + " but no " + cameraName(n) + ": the cameras must be cam0, cam1, ... without a gap");
    }
    if (n < 2) fail("a rig needs at least two cameras (cam0 and cam1), found " + std::to_string(n));
    return n;
  }

  bool allHave(const YAML::Node& root, int n, const char* key, int from) const {
    for (int k = from; k < n; ++k)
      if (!YamlDoc::find(YamlDoc::find(root, cameraName(k)), key).IsDefined()) return false;
    return true;
  }

  std::vector<BodyPose> chainPoses(const YAML::Node& root, int n) const {
    std::vector<BodyPose> poses(static_cast<size_t>(n));
    Eigen::Matrix4d bodyFromCam = Eigen::Matrix4d::Identity();
    for (int k = 1; k < n; ++k) {
      const std::string key = cameraName(k) + ".T_cn_cnm1";
      const YAML::Node node = YamlDoc::find(YamlDoc::find(root, cameraName(k)), "T_cn_cnm1");
      if (!node.IsDefined())
        fail("missing key \"" + key + "\": the chain from " + cameraName(k - 1) + " to " + cameraName(k) +
             " is broken (nor do all cameras have T_cam_imu or T_imu_cam to pose them by)");
      const Eigen::Matrix4d T = readPose(node, key);
      checkRotation(T, key);
      bodyFromCam = bodyFromCam * calib::rigidInverse(T);
      poses[size_t(k)] = {bodyFromCam.topLeftCorner<3, 3>(), bodyFromCam.topRightCorner<3, 1>()};
    }
    return poses;
  }

  std::vector<BodyPose> imuPoses(const YAML::Node& root, int n) const {
    const bool camImu = allHave(root, n, "T_cam_imu", 0);
    std::vector<BodyPose> poses;
    for (int k = 0; k < n; ++k) {
      const std::string key = cameraName(k) + (camImu ? ".T_cam_imu" : ".T_imu_cam");
      const Eigen::Matrix4d T =
          readPose(YamlDoc::find(YamlDoc::find(root, cameraName(k)), camImu ? "T_cam_imu" : "T_imu_cam"), key);
      checkRotation(T, key);
      const Eigen::Matrix4d bodyFromCam = camImu ? calib::rigidInverse(T) : T;
      poses.push_back({bodyFromCam.topLeftCorner<3, 3>(), bodyFromCam.topRightCorner<3, 1>()});
    }
    return poses;
  }

  // The pose check without the baseline's (a camera may sit at the IMU's origin).
  void checkRotation(const Eigen::Matrix4d& T, const std::string& key) const {
    try {
      calib::checkPose(T.topLeftCorner<3, 3>(), Eigen::Vector3d::UnitX(), key);
    } catch (const Error& e) {
      fail(e.what());
    }
  }

  calib::YamlDoc doc_;

  [[noreturn]] void fail(const std::string& problem) const { doc_.fail(problem); }
  YAML::Node require(const YAML::Node& parent, const std::string& key, const std::string& prefix) const {
    return doc_.require(parent, key, prefix);
  }
  std::vector<double> numbers(const YAML::Node& node, const std::string& key) const { return doc_.numbers(node, key); }
  std::string text(const YAML::Node& node, const std::string& key) const { return doc_.text(node, key); }

  Camera readCamera(const YAML::Node& root, const std::string& name) const {
    const YAML::Node node = require(root, name, "");
    const std::string cameraModel = text(require(node, "camera_model", name), name + ".camera_model");
    // Kalibr always writes distortion_model; other tools omit it for omni/eucm/ds.
    const YAML::Node distortionNode = YamlDoc::find(node, "distortion_model");
    const YAML::Node coeffsNode = YamlDoc::find(node, "distortion_coeffs");
    const std::string distortion =
        distortionNode.IsDefined() ? text(distortionNode, name + ".distortion_model") : "none";
    const std::vector<double> coeffs =
        coeffsNode.IsDefined() ? numbers(coeffsNode, name + ".distortion_coeffs") : std::vector<double>();
    const std::vector<double> intrinsics = numbers(require(node, "intrinsics", name), name + ".intrinsics");
    const std::vector<double> resolution = numbers(require(node, "resolution", name), name + ".resolution");
    if (resolution.size() != 2) fail(name + ".resolution must be [width, height]");
    for (double v : resolution)
      if (v != std::floor(v) || v < 1 || v > 1e6) fail(name + ".resolution must hold two positive integers");

    Camera cam;
    cam.model = modelFor(name, cameraModel, distortion);
    cam.width = int(resolution[0]);
    cam.height = int(resolution[1]);
    cam.params = intrinsicsInCameraOrder(name, cameraModel, intrinsics);
    appendDistortion(name, distortion, coeffs, cam.params);
    return cam;
  }

  CameraModel modelFor(const std::string& name, const std::string& cameraModel, const std::string& distortion) const {
    static const char* supported =
        "supported: pinhole+equidistant, pinhole+radtan, pinhole+none, omni+none, omni+radtan, eucm+none, ds+none";
    // pinhole+none is pinhole+radtan with zero coefficients (appendDistortion).
    const std::string kalibrDistortion = cameraModel == "pinhole" && distortion == "none" ? "radtan" : distortion;
    bool knownCamera = false, found = false;
    CameraModel model{};
    models::forEachModelType([&](auto tag) {
      using M = typename decltype(tag)::type;
      if (cameraModel != M::kKalibrModel) return;
      knownCamera = true;
      if (kalibrDistortion == M::kKalibrDistortion) model = M::kModel, found = true;
    });
    if (found) return model;
    if (!knownCamera) fail(name + ": unknown camera_model '" + cameraModel + "' (" + supported + ")");
    fail(name + ": unsupported camera model " + cameraModel + "+" + distortion + " (" + supported + ")");
  }

  // Kalibr lists the model parameters first ([xi fu fv pu pv]); Camera puts them last.
  std::vector<double> intrinsicsInCameraOrder(const std::string& name, const std::string& cameraModel,
                                              const std::vector<double>& v) const {
    const char* layout = cameraModel == "pinhole" ? "[fu fv pu pv]"
                         : cameraModel == "omni"  ? "[xi fu fv pu pv]"
                         : cameraModel == "eucm"  ? "[alpha beta fu fv pu pv]"
                                                  : "[xi alpha fu fv pu pv]";
    const size_t extra = cameraModel == "pinhole" ? 0 : cameraModel == "omni" ? 1 : 2;
    if (v.size() != 4 + extra)
      fail(name + ".intrinsics has " + std::to_string(v.size()) + " values but camera_model " + cameraModel +
           " needs " + std::to_string(4 + extra) + " " + layout);
    std::vector<double> out(v.begin() + long(extra), v.end());
    out.insert(out.end(), v.begin(), v.begin() + long(extra));
    return out;
  }

  void appendDistortion(const std::string& name, const std::string& distortion, const std::vector<double>& coeffs,
                        std::vector<double>& params) const {
    const std::string key = name + ".distortion_coeffs";
    if (distortion == "none") {
      for (double c : coeffs)
        if (c != 0) fail(key + " must be empty or zero for distortion_model none");
      if (params.size() == 4) params.insert(params.end(), 4, 0.0);  // pinhole+none = radtan with zeros
      return;
    }
    if (coeffs.size() != 4)
      fail(key + " has " + std::to_string(coeffs.size()) + " values but distortion_model " + distortion + " needs 4");
    params.insert(params.end(), coeffs.begin(), coeffs.end());
  }

  // cam1.T_cn_cnm1 when present; else, as in camchain-imucam files (Kalibr: T_cam_imu maps
  // IMU to camera coordinates; OpenVINS: T_imu_cam the other way), the cameras' IMU poses:
  // T_c1_c0 = T_c1_imu T_c0_imu^-1. Returns the name the pose goes by in messages.
  std::string stereoPose(const YAML::Node& root, Rig& rig) const {
    const YAML::Node cam0 = YamlDoc::find(root, "cam0"), cam1 = YamlDoc::find(root, "cam1");
    Eigen::Matrix4d T;
    std::string poseName = "T_cn_cnm1";
    if (YamlDoc::find(cam1, "T_cn_cnm1").IsDefined()) {
      T = readPose(YamlDoc::find(cam1, "T_cn_cnm1"), "cam1.T_cn_cnm1");
    } else if (YamlDoc::find(cam0, "T_cam_imu").IsDefined() && YamlDoc::find(cam1, "T_cam_imu").IsDefined()) {
      T = readPose(YamlDoc::find(cam1, "T_cam_imu"), "cam1.T_cam_imu") *
          calib::rigidInverse(readPose(YamlDoc::find(cam0, "T_cam_imu"), "cam0.T_cam_imu"));
      poseName = "T_cam_imu";
    } else if (YamlDoc::find(cam0, "T_imu_cam").IsDefined() && YamlDoc::find(cam1, "T_imu_cam").IsDefined()) {
      T = calib::rigidInverse(readPose(YamlDoc::find(cam1, "T_imu_cam"), "cam1.T_imu_cam")) *
          readPose(YamlDoc::find(cam0, "T_imu_cam"), "cam0.T_imu_cam");
      poseName = "T_imu_cam";
    } else {
      fail(
          "missing key \"cam1.T_cn_cnm1\" (the stereo pose; nor do both cameras have T_cam_imu or T_imu_cam to "
          "derive it from)");
    }
    rig.R = T.topLeftCorner<3, 3>();
    rig.t = T.topRightCorner<3, 1>();
    return poseName;
  }

  Eigen::Matrix4d readPose(const YAML::Node& node, const std::string& key) const {
    if (!node.IsSequence() || node.size() != 4) fail(key + " must be a 4x4 matrix (4 rows of 4 numbers)");
    Eigen::Matrix4d T;
    for (int r = 0; r < 4; ++r) {
      const std::vector<double> row = numbers(node[r], key + "[" + std::to_string(r) + "]");
      if (row.size() != 4) fail(key + " must be a 4x4 matrix (4 rows of 4 numbers)");
      for (int c = 0; c < 4; ++c) T(r, c) = row[size_t(c)];
    }
    if ((T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9)
      fail(key + " last row must be [0, 0, 0, 1], got [" + formatNumber(T(3, 0)) + ", " + formatNumber(T(3, 1)) + ", " +
           formatNumber(T(3, 2)) + ", " + formatNumber(T(3, 3)) + "]");
    return T;
  }
};

// ------------------------------------------------------------------------------------------
// Writing.

struct KalibrCamera {
  const char* cameraModel;
  const char* distortionModel;
  std::vector<double> intrinsics;
  std::vector<double> coeffs;
};

// Kalibr lists the projection's own parameters before fx fy cx cy ([xi fu fv pu pv]) and
// the distortion's (the model's last kDistortionParams) as distortion_coeffs.
KalibrCamera toKalibr(const Camera& cam) {
  KalibrCamera k{nullptr, nullptr, {}, {}};
  models::visitModelType(cam.model, [&](auto tag) {
    using M = typename decltype(tag)::type;
    const auto pinhole = cam.params.begin() + 4, distortion = cam.params.end() - M::kDistortionParams;
    k.cameraModel = M::kKalibrModel;
    k.distortionModel = M::kKalibrDistortion;
    k.intrinsics.assign(pinhole, distortion);
    k.intrinsics.insert(k.intrinsics.end(), cam.params.begin(), pinhole);
    k.coeffs.assign(distortion, cam.params.end());
  });
  if (!k.cameraModel) throw Error("saveKalibr: unknown camera model");
  return k;
}

void writeCamera(std::ostream& os, const Camera& cam) {
  const KalibrCamera k = toKalibr(cam);
  os << "  camera_model: " << k.cameraModel << "\n"
     << "  distortion_coeffs: " << numberList(k.coeffs) << "\n"
     << "  distortion_model: " << k.distortionModel << "\n"
     << "  intrinsics: " << numberList(k.intrinsics) << "\n"
     << "  resolution: [" << cam.width << ", " << cam.height << "]\n";
}

}  // namespace

Rig loadKalibr(const std::string& path) { return KalibrReader(path).read(calib::readTextFile(path)); }

Rig parseKalibr(const std::string& yaml, const std::string& name) { return KalibrReader(name).read(yaml); }

CameraRig parseKalibrRig(const std::string& yaml, const std::string& name) {
  CameraRig rig = KalibrReader(name).readRig(yaml);
  calib::checkCameraRig(rig, name);
  return rig;
}

void saveKalibrRig(const CameraRig& rig, const std::string& path) {
  try {
    rig.validate();
  } catch (const Error& e) {
    throw Error(path + ": not saving an invalid rig: " + e.what());
  }
  std::ostringstream os;
  os << "# Kalibr camchain written by curvestereo. camK's T_cn_cnm1 maps camK-1 to camK.\n";
  for (int k = 0; k < rig.size(); ++k) {
    os << "cam" << k << ":\n";
    if (k > 0) {
      const Rig pair = pairRig(rig, k - 1, k);
      os << "  T_cn_cnm1:\n";
      for (int r = 0; r < 3; ++r)
        os << "  - " << numberList({pair.R(r, 0), pair.R(r, 1), pair.R(r, 2), pair.t(r)}) << "\n";
      os << "  - [0.0, 0.0, 0.0, 1.0]\n";
    }
    writeCamera(os, rig.cameras[size_t(k)]);
  }
  calib::writeTextFile(path, os.str());
}

void saveKalibr(const Rig& rig, const std::string& path) {
  calib::checkRigBeforeSaving(rig, path);  // never write a file that loadKalibr would refuse
  std::ostringstream os;
  os << "# Kalibr camchain written by curvestereo. T_cn_cnm1 maps cam0 to cam1: X1 = R*X0 + t.\n";
  os << "cam0:\n";
  writeCamera(os, rig.cam0);
  os << "cam1:\n  T_cn_cnm1:\n";
  for (int r = 0; r < 3; ++r) os << "  - " << numberList({rig.R(r, 0), rig.R(r, 1), rig.R(r, 2), rig.t(r)}) << "\n";
  os << "  - [0.0, 0.0, 0.0, 1.0]\n";
  writeCamera(os, rig.cam1);

  calib::writeTextFile(path, os.str());
}

}  // namespace cs

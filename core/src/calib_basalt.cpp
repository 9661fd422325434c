// Basalt calibration.json (cereal JSON, read with yaml-cpp: JSON is YAML 1.2 flow
// syntax). Written from Basalt's calibration format: value0.T_imu_cam[i] is the pose of
// camera i in the IMU frame (X_imu = R_i X_cam + p_i; quaternion qx qy qz qw, Hamilton,
// scalar last), value0.intrinsics[i] names its parameters, value0.resolution[i] = [w, h].
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "calib_common.hpp"
#include "curvestereo/camera_models.hpp"
#include "curvestereo/camera_rig.hpp"
#include "curvestereo/rig.hpp"

namespace cs {

namespace {

using calib::dotted;
using calib::exactNumber;
using calib::YamlDoc;

// Each camera_type's parameter names in Basalt's order. Camera's layout is
// [fx fy cx cy extra...], and for kb4 / ds / eucm the extras come in the same order
// (ds: xi then alpha, as Camera::doubleSphere takes them).
struct BasaltType {
  const char* name;
  std::vector<std::string> params;
};

const std::vector<BasaltType>& basaltTypes() {
  static const std::vector<BasaltType> types = {
      {"kb4", {"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"}},
      {"ds", {"fx", "fy", "cx", "cy", "xi", "alpha"}},
      {"eucm", {"fx", "fy", "cx", "cy", "alpha", "beta"}},
      {"ucm", {"fx", "fy", "cx", "cy", "alpha"}},
      {"pinhole", {"fx", "fy", "cx", "cy"}},
      {"pinhole-radtan8", {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6", "rpmax"}},
  };
  return types;
}

// type's parameters are `names`, in that order.
template <size_t N>
bool sameNames(const BasaltType& type, const char* const (&names)[N]) {
  return std::equal(type.params.begin(), type.params.end(), std::begin(names), std::end(names));
}

const char* kSupportedTypes = "supported: kb4, ds, eucm, ucm, pinhole, pinhole-radtan8 with k3..k6 = 0";

std::string joined(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : " ") + w;
  return out;
}

struct Pose {
  Eigen::Matrix3d R;
  Eigen::Vector3d p;
};

// Basalt's ucm divides by alpha |X| + (1 - alpha) z; the unified model (Kalibr omni) by
// z + xi |X|. They are the same lens for xi = alpha / (1 - alpha) and
// f_unified = f_ucm / (1 - alpha). At alpha = 1 (xi infinite) ucm is the extended
// unified model with beta = 1, exactly.
Camera cameraFromUcm(const std::vector<double>& v) {
  const double alpha = v[4];
  if (alpha == 1.0) return Camera::extendedUnified(0, 0, v[0], v[1], v[2], v[3], 1.0, 1.0);
  const double s = 1.0 / (1.0 - alpha);
  return Camera::unified(0, 0, v[0] * s, v[1] * s, v[2], v[3], alpha * s);
}

class BasaltReader {
 public:
  explicit BasaltReader(std::string name) : doc_(std::move(name)) {}

  // The calibration's object: cereal names the archive's root value0; the object itself is
  // accepted as well.
  YAML::Node calibrationObject(const std::string& text) {
    const YAML::Node root = doc_.parse(text, "JSON");
    if (!root.IsMap())
      doc_.fail("not a Basalt calibration (expected a JSON object with value0.T_imu_cam, intrinsics and resolution)");
    const YAML::Node value0 = YamlDoc::find(root, "value0");
    prefix_ = value0.IsDefined() ? "value0" : "";
    return value0.IsDefined() ? value0 : root;
  }

  Rig read(const std::string& text) {
    const YAML::Node v = calibrationObject(text);
    const YAML::Node poses = twoOrMore(v, "T_imu_cam");
    const YAML::Node intrinsics = twoOrMore(v, "intrinsics");
    const YAML::Node resolution = twoOrMore(v, "resolution");
    Rig rig;
    rig.cam0 = readCamera(intrinsics[0], resolution[0], 0);
    rig.cam1 = readCamera(intrinsics[1], resolution[1], 1);
    const Pose p0 = readPose(poses[0], 0), p1 = readPose(poses[1], 1);
    // X_imu = R0 X0 + p0 = R1 X1 + p1, so X1 = R1^T R0 X0 + R1^T (p0 - p1).
    rig.R = p1.R.transpose() * p0.R;
    rig.t = p1.R.transpose() * (p0.p - p1.p);
    calib::checkRig(rig, doc_.name(), "T_imu_cam");
    return rig;
  }

  // Every camera, posed in the IMU frame; the three lists must have one entry per camera.
  CameraRig readRig(const std::string& text) {
    const YAML::Node v = calibrationObject(text);
    const YAML::Node poses = twoOrMore(v, "T_imu_cam");
    const YAML::Node intrinsics = twoOrMore(v, "intrinsics");
    const YAML::Node resolution = twoOrMore(v, "resolution");
    if (intrinsics.size() != poses.size() || resolution.size() != poses.size())
      doc_.fail(key("T_imu_cam") + ", " + key("intrinsics") + " and " + key("resolution") + " have " +
                std::to_string(poses.size()) + ", " + std::to_string(intrinsics.size()) + " and " +
                std::to_string(resolution.size()) + " entries: each needs one per camera");
    CameraRig rig;
    for (int i = 0; i < int(poses.size()); ++i) {
      rig.cameras.push_back(readCamera(intrinsics[i], resolution[i], i));
      const Pose pose = readPose(poses[i], i);
      rig.poses.push_back({pose.R, pose.p});
    }
    return rig;
  }

 private:
  YamlDoc doc_;
  std::string prefix_;

  std::string key(const std::string& name) const { return dotted(prefix_, name); }
  std::string key(const std::string& list, int i) const { return key(list) + "[" + std::to_string(i) + "]"; }

  // A list with one entry per camera; a stereo rig needs two.
  YAML::Node twoOrMore(const YAML::Node& v, const std::string& name) const {
    const YAML::Node node = doc_.require(v, name, prefix_);
    if (!node.IsSequence()) doc_.fail(key(name) + " must be a list with one entry per camera" + YamlDoc::lineOf(node));
    if (node.size() < 2)
      doc_.fail(key(name) + " has " + std::to_string(node.size()) + " entr" + (node.size() == 1 ? "y" : "ies") +
                "; a stereo rig needs two cameras");
    return node;
  }

  Pose readPose(const YAML::Node& node, int i) const {
    const std::string k = key("T_imu_cam", i);
    if (!node.IsMap()) doc_.fail(k + " must be an object {px, py, pz, qx, qy, qz, qw}" + YamlDoc::lineOf(node));
    auto num = [&](const char* name) { return doc_.number(doc_.require(node, name, k), k + "." + name); };
    const Eigen::Vector3d p(num("px"), num("py"), num("pz"));
    // Eigen's constructor takes w first; the file stores it last.
    Eigen::Quaterniond q(num("qw"), num("qx"), num("qy"), num("qz"));
    const double norm = q.norm();
    // Hand-written quaternions carry a few digits; a norm far from 1 is a wrong value or order.
    if (!(std::abs(norm - 1.0) < 1e-3))
      doc_.fail(k + " quaternion (qx, qy, qz, qw) is not a unit quaternion (norm " + calib::formatNumber(norm, 10) +
                ")");
    q.normalize();
    return {q.toRotationMatrix(), p};
  }

  const BasaltType& typeNamed(const std::string& type, const std::string& k) const {
    for (const BasaltType& t : basaltTypes())
      if (type == t.name) return t;
    doc_.fail(k + ".camera_type '" + type + "' is not supported (" + kSupportedTypes + ")");
  }

  // The named parameters in the type's order. A name the type does not have usually
  // means the wrong camera_type (e.g. xi under eucm), so it is an error, not ignored.
  std::vector<double> namedParams(const YAML::Node& node, const BasaltType& type, const std::string& k) const {
    if (!node.IsMap()) doc_.fail(k + " must be an object of named parameters" + YamlDoc::lineOf(node));
    for (const auto& entry : node) {
      const std::string name = entry.first.IsScalar() ? entry.first.Scalar() : std::string("?");
      if (std::find(type.params.begin(), type.params.end(), name) == type.params.end())
        doc_.fail(k + " has parameter '" + name + "', which camera_type " + type.name + " does not have (it has " +
                  joined(type.params) + ")" + YamlDoc::lineOf(entry.first));
    }
    std::vector<double> values;
    for (const std::string& name : type.params)
      values.push_back(doc_.number(doc_.require(node, name, k), k + "." + name));
    return values;
  }

  Camera cameraFor(const BasaltType& type, const std::vector<double>& v, const std::string& k) const {
    const std::string name = type.name;
    if (name == "ucm") {
      if (!(v[4] >= 0 && v[4] <= 1)) doc_.fail(k + ".alpha = " + calib::formatNumber(v[4]) + " is outside [0, 1]");
      return cameraFromUcm(v);
    }
    if (name == "pinhole") return Camera::pinholeRadtan(0, 0, v[0], v[1], v[2], v[3]);
    if (name == "pinhole-radtan8") {
      // Rational radial distortion (k3..k6) has no counterpart here; with them zero it is
      // radtan. rpmax only bounds Basalt's valid region and is not needed.
      for (size_t i = 8; i < 12; ++i)
        if (v[i] != 0)
          doc_.fail(k + "." + type.params[i] + " = " + calib::formatNumber(v[i]) +
                    ": pinhole-radtan8 is read only with k3..k6 = 0 (k1 k2 p1 p2 radtan)");
      return Camera::pinholeRadtan(0, 0, v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]);
    }
    // kb4, ds, eucm: the model whose parameters Basalt lists as Camera does (sameLayout).
    Camera cam;
    models::forEachModelType([&](auto tag) {
      using M = typename decltype(tag)::type;
      if (sameNames(type, M::kParamNames)) cam.model = M::kModel;
    });
    cam.params = v;
    return cam;
  }

  Camera readCamera(const YAML::Node& entry, const YAML::Node& resolution, int i) const {
    const std::string k = key("intrinsics", i);
    if (!entry.IsMap()) doc_.fail(k + " must be an object {camera_type, intrinsics}" + YamlDoc::lineOf(entry));
    const std::string typeName = doc_.text(doc_.require(entry, "camera_type", k), k + ".camera_type");
    const BasaltType& type = typeNamed(typeName, k);
    Camera cam = cameraFor(type, namedParams(doc_.require(entry, "intrinsics", k), type, k + ".intrinsics"), k);
    const std::string rk = key("resolution", i);
    if (!resolution.IsSequence() || resolution.size() != 2)
      doc_.fail(rk + " must be [width, height]" + YamlDoc::lineOf(resolution));
    cam.width = doc_.integer(resolution[0], rk + "[0]", 1, 1000000);
    cam.height = doc_.integer(resolution[1], rk + "[1]", 1, 1000000);
    return cam;
  }
};

// ------------------------------------------------------------------------------------------
// Writing.

// The Basalt type that lists the camera's parameters as Camera does (the model's
// kParamNames, in order: kb4, ds, eucm); null for none.
const BasaltType* sameLayout(const Camera& cam) {
  const BasaltType* found = nullptr;
  models::visitModelType(cam.model, [&](auto tag) {
    using M = typename decltype(tag)::type;
    for (const BasaltType& t : basaltTypes())
      if (sameNames(t, M::kParamNames)) found = &t;
  });
  return found;
}

// The Basalt type and its parameters (in basaltTypes() order) for a camera; cs::Error
// for what Basalt cannot represent.
std::pair<const char*, std::vector<double>> toBasalt(const Camera& cam, const std::string& path) {
  const std::vector<double>& p = cam.params;
  if (const BasaltType* type = sameLayout(cam)) return {type->name, p};
  if (cam.model == CameraModel::Unified) {
    // The inverse of cameraFromUcm: alpha = xi / (1 + xi), f_ucm = f / (1 + xi).
    const double s = 1.0 / (1.0 + p[4]);
    return {"ucm", {p[0] * s, p[1] * s, p[2], p[3], p[4] * s}};
  }
  if (cam.model == CameraModel::PinholeRadtan) {
    if (p[4] == 0 && p[5] == 0 && p[6] == 0 && p[7] == 0) return {"pinhole", {p[0], p[1], p[2], p[3]}};
    // Basalt's radtan is pinhole-radtan8; with k3..k6 = 0 it is radtan. rpmax bounds
    // the undistorted radius Basalt accepts: the widest image corner, with a margin.
    const double rpmax = 1.05 * std::tan(std::min(BuiltCamera(cam).maxAngle(), 89.0 * M_PI / 180.0));
    return {"pinhole-radtan8", {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], 0, 0, 0, 0, rpmax}};
  }
  if (cam.model == CameraModel::Mei)
    throw Error(path +
                ": Basalt calibrations cannot represent the mei (unified + radtan) camera model: write "
                "Kalibr or VINS-Fusion instead");
  throw Error(path + ": saveBasalt: unknown camera model");
}

const BasaltType& typeByName(const char* name) {
  for (const BasaltType& t : basaltTypes())
    if (std::string(name) == t.name) return t;
  throw Error(std::string("unknown Basalt camera type ") + name);
}

void writePose(std::ostream& os, const Eigen::Matrix3d& R, const Eigen::Vector3d& p) {
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;  // one of the two signs, for tidy files
  os << "            {\n";
  const std::pair<const char*, double> fields[] = {{"px", p.x()}, {"py", p.y()}, {"pz", p.z()}, {"qx", q.x()},
                                                   {"qy", q.y()}, {"qz", q.z()}, {"qw", q.w()}};
  for (size_t i = 0; i < 7; ++i)
    os << "                \"" << fields[i].first << "\": " << exactNumber(fields[i].second) << (i < 6 ? "," : "")
       << "\n";
  os << "            }";
}

void writeIntrinsics(std::ostream& os, const Camera& cam, const std::string& path) {
  const auto [typeName, values] = toBasalt(cam, path);
  const BasaltType& type = typeByName(typeName);
  os << "            {\n                \"camera_type\": \"" << typeName << "\",\n"
     << "                \"intrinsics\": {\n";
  for (size_t i = 0; i < values.size(); ++i)
    os << "                    \"" << type.params[i] << "\": " << exactNumber(values[i])
       << (i + 1 < values.size() ? "," : "") << "\n";
  os << "                }\n            }";
}

std::string zeros(int n) {
  std::string out = "[";
  for (int i = 0; i < n; ++i) out += i ? ", 0.0" : "0.0";
  return out + "]";
}

}  // namespace

Rig parseBasalt(const std::string& json, const std::string& name) { return BasaltReader(name).read(json); }

CameraRig parseBasaltRig(const std::string& json, const std::string& name) {
  CameraRig rig = BasaltReader(name).readRig(json);
  calib::checkCameraRig(rig, name);
  return rig;
}

Rig loadBasalt(const std::string& path) { return BasaltReader(path).read(calib::readTextFile(path)); }

void saveBasalt(const Rig& rig, const std::string& path) {
  calib::checkRigBeforeSaving(rig, path);
  std::ostringstream os;
  os << "{\n    \"value0\": {\n        \"T_imu_cam\": [\n";
  // Camera 0 defines the IMU frame here; camera 1's pose in it is the inverse of (R, t):
  // X0 = R^T X1 - R^T t.
  writePose(os, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  os << ",\n";
  writePose(os, rig.R.transpose(), -(rig.R.transpose() * rig.t));
  os << "\n        ],\n        \"intrinsics\": [\n";
  writeIntrinsics(os, rig.cam0, path);
  os << ",\n";
  writeIntrinsics(os, rig.cam1, path);
  os << "\n        ],\n        \"resolution\": [\n"
     << "            [" << rig.cam0.width << ", " << rig.cam0.height << "],\n"
     << "            [" << rig.cam1.width << ", " << rig.cam1.height << "]\n        ],\n";
  // Basalt's loader expects the IMU fields too; a stereo calibration has none, so they
  // are neutral placeholders (no bias, unit scale, 200 Hz, zero noise).
  os << "        \"calib_accel_bias\": " << zeros(9) << ",\n"
     << "        \"calib_gyro_bias\": " << zeros(12) << ",\n"
     << "        \"imu_update_rate\": 200.0,\n"
     << "        \"accel_noise_std\": " << zeros(3) << ",\n"
     << "        \"gyro_noise_std\": " << zeros(3) << ",\n"
     << "        \"accel_bias_std\": " << zeros(3) << ",\n"
     << "        \"gyro_bias_std\": " << zeros(3) << ",\n"
     << "        \"cam_time_offset_ns\": 0,\n"
     << "        \"vignette\": []\n    }\n}\n";
  calib::writeTextFile(path, os.str());
}

}  // namespace cs

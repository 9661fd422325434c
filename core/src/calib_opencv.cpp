// OpenCV FileStorage stereo calibrations (YAML or XML), written from OpenCV's
// documentation of FileStorage, calib3d (stereoCalibrate: X2 = R X1 + T) and the fisheye
// module (cv::fisheye: Kannala-Brandt with D = k1..k4).
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <sstream>
#include <string>
#include <vector>

#include "calib_common.hpp"
#include "calib_opencv.hpp"
#include "curvestereo/rig.hpp"

namespace cs {

namespace {

using calib::CvStorage;
using calib::CvValue;
using calib::exactNumber;
using calib::YamlDoc;

// ------------------------------------------------------------------------------------------
// YAML text -> the same entries the XML reader gives.

CvValue matrixFromYaml(const YamlDoc& doc, const std::string& key, const YAML::Node& node) {
  CvValue v;
  v.kind = CvValue::Kind::Matrix;
  v.where = YamlDoc::lineOf(node);
  v.rows = doc.integer(doc.require(node, "rows", key), key + ".rows", 0, 1000000);
  v.cols = doc.integer(doc.require(node, "cols", key), key + ".cols", 0, 1000000);
  v.data = doc.numbers(doc.require(node, "data", key), key + ".data");
  if (double(v.data.size()) != double(v.rows) * double(v.cols))
    doc.fail(key + " is " + std::to_string(v.rows) + "x" + std::to_string(v.cols) + " but its data has " +
             std::to_string(v.data.size()) + " values" + v.where);
  return v;
}

CvValue valueFromYaml(const YamlDoc& doc, const std::string& key, const YAML::Node& node) {
  const bool matrix = node.IsMap() && YamlDoc::find(node, "rows").IsDefined() &&
                      YamlDoc::find(node, "cols").IsDefined() && YamlDoc::find(node, "data").IsDefined();
  if (matrix) return matrixFromYaml(doc, key, node);
  CvValue v;
  v.where = YamlDoc::lineOf(node);
  if (node.IsScalar()) {
    v.kind = CvValue::Kind::Scalar;
    v.text = node.Scalar();
  } else if (node.IsSequence()) {
    v.kind = CvValue::Kind::List;
    v.data = doc.numbers(node, key);
  }
  return v;
}

CvStorage storageFromYaml(const YamlDoc& doc, const std::string& text) {
  const YAML::Node root = doc.parse(text, "YAML");
  if (!root.IsMap()) doc.fail("not an OpenCV FileStorage file (expected a mapping with K1, D1, K2, D2, R, T)");
  CvStorage storage;
  for (const auto& entry : root) {
    if (!entry.first.IsScalar()) continue;
    const std::string key = entry.first.Scalar();
    if (!storage.count(key)) storage[key] = valueFromYaml(doc, key, entry.second);
  }
  return storage;
}

// ------------------------------------------------------------------------------------------
// Entries -> Rig.

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

enum class Distortion { Unknown, Fisheye, Radtan };

class OpenCvRigReader {
 public:
  OpenCvRigReader(std::string name, const CvStorage& storage, const CalibHints& hints)
      : name_(std::move(name)), s_(storage), hints_(hints) {}

  Rig read() const {
    if (!find("K1") && !find("M1") && !find("R") && !find("D1"))
      fail("not an OpenCV stereo calibration (no K1/M1, D1, K2/M2, D2, R or T)");
    const auto [width, height] = imageSize();
    const Distortion model = distortionModel();
    Rig rig;
    rig.cam0 = camera(0, model, width, height);
    rig.cam1 = camera(1, model, width, height);
    rig.R = rotation();
    rig.t = translation();
    calib::checkRig(rig, name_, "R, T");
    return rig;
  }

 private:
  std::string name_;
  const CvStorage& s_;
  CalibHints hints_;

  [[noreturn]] void fail(const std::string& problem) const { throw Error(calib::oneLine(name_ + ": " + problem)); }

  const CvValue* find(const std::string& key) const {
    const auto it = s_.find(key);
    return it == s_.end() ? nullptr : &it->second;
  }

  // An !!opencv-matrix, or a plain list as cv::FileStorage writes a cv::Vec (YAML [a, b, c],
  // XML text "a b c"): n values are an n x 1 column, 9 values a 3x3 matrix.
  CvValue matrix(const std::string& key, const std::string& alias, const std::string& hint) const {
    const CvValue* v = find(key);
    if (!v && !alias.empty()) v = find(alias);
    const std::string names = alias.empty() ? "\"" + key + "\"" : "\"" + key + "\" (or \"" + alias + "\")";
    if (!v) fail("missing key " + names + hint);
    if (v->kind == CvValue::Kind::Matrix) return *v;
    CvValue out = *v;
    const bool list = v->kind == CvValue::Kind::List ||
                      (v->kind == CvValue::Kind::Scalar && calib::parseNumberList(v->text, out.data));
    if (!list || out.data.empty())
      fail(key + " must be an !!opencv-matrix with rows, cols and data, or a list of numbers" + v->where);
    out.kind = CvValue::Kind::Matrix;
    const bool square = out.data.size() == 9;
    out.rows = square ? 3 : int(out.data.size());
    out.cols = square ? 3 : 1;
    return out;
  }

  // A whole number from a scalar entry (YAML plain scalar or XML text).
  int integer(const CvValue& v, const std::string& key) const {
    std::vector<double> n;
    if (v.kind != CvValue::Kind::Scalar || !calib::parseNumberList(v.text, n) || n.size() != 1 ||
        !calib::wholeInRange(n[0], 1, 1e6))
      fail(key + " must be a positive whole number" + v.where);
    return int(n[0]);
  }

  std::pair<int, int> imageSize() const {
    const CvValue* w = find("image_width");
    const CvValue* h = find("image_height");
    if (w && h) return {integer(*w, "image_width"), integer(*h, "image_height")};
    if (!w && !h) {
      for (const char* key : {"image_size", "imageSize"})
        if (find(key)) return listedImageSize(*find(key), key);
      if (hints_.width > 0 && hints_.height > 0) return {hints_.width, hints_.height};
    }
    fail(std::string("missing key \"") + (w ? "image_height" : "image_width") +
         "\" (the image size in pixels, which stereoCalibrate does not store: add image_width and image_height, or "
         "pass --image-size WxH)");
  }

  std::pair<int, int> listedImageSize(const CvValue& v, const std::string& key) const {
    std::vector<double> wh = v.data;
    if (v.kind == CvValue::Kind::Scalar) calib::parseNumberList(v.text, wh);
    if (wh.size() != 2 || !calib::wholeInRange(wh[0], 1, 1e6) || !calib::wholeInRange(wh[1], 1, 1e6))
      fail(key + " must be [width, height] in pixels" + v.where);
    return {int(wh[0]), int(wh[1])};
  }

  Distortion distortionModel() const {
    const CvValue* v = find("distortion_model");
    if (!v) return Distortion::Unknown;
    if (v->kind != CvValue::Kind::Scalar) fail("distortion_model must be a string" + v->where);
    const std::string m = lower(v->text);
    if (m == "fisheye" || m == "equidistant" || m == "kannala_brandt" || m == "kannala-brandt")
      return Distortion::Fisheye;
    if (m == "radtan" || m == "plumb_bob" || m == "rational_polynomial") return Distortion::Radtan;
    fail("distortion_model '" + v->text +
         "' is not supported (fisheye / equidistant: Kannala-Brandt 4; radtan / plumb_bob: k1 k2 p1 p2)" + v->where);
  }

  // K must be [fx 0 cx; 0 fy cy; 0 0 1]: the camera models here have no skew.
  std::vector<double> pinhole(const CvValue& K, const std::string& key) const {
    if (K.rows != 3 || K.cols != 3) fail(key + " must be 3x3" + K.where);
    const std::vector<double>& k = K.data;
    if (k[1] != 0)
      fail(key + " has skew K[0][1] = " + calib::formatNumber(k[1]) + ", which the camera models here do not have" +
           K.where);
    if (k[3] != 0 || k[6] != 0 || k[7] != 0 || k[8] != 1)
      fail(key + " must have the form [fx 0 cx; 0 fy cy; 0 0 1]" + K.where);
    return {k[0], k[4], k[2], k[5]};
  }

  // D of a pinhole camera in OpenCV's order k1 k2 p1 p2 [k3 [k4 k5 k6 [s1..s4 [tx ty]]]]:
  // the terms after p2 must be zero, since the radtan model here stops at p2.
  std::vector<double> radtan(const CvValue& D, const std::string& key) const {
    const size_t n = D.data.size();
    if (n != 4 && n != 5 && n != 8 && n != 12 && n != 14)
      fail(key + " has " + std::to_string(n) + " values; a pinhole (radtan) D has 4, 5, 8, 12 or 14" + D.where);
    for (size_t i = 4; i < n; ++i)
      if (D.data[i] != 0)
        fail(key + "[" + std::to_string(i) + "] = " + calib::formatNumber(D.data[i]) +
             " is not zero: only k1 k2 p1 p2 of OpenCV's pinhole distortion are supported" + D.where);
    return {D.data.begin(), D.data.begin() + 4};
  }

  Camera camera(int i, Distortion model, int width, int height) const {
    const std::string n = std::to_string(i + 1);
    const CvValue K = matrix("K" + n, "M" + n, "");
    const CvValue D = matrix("D" + n, "", "");
    const std::string kKey = find("K" + n) ? "K" + n : "M" + n;
    const std::string dKey = "D" + n;
    if (D.rows != 1 && D.cols != 1) fail(dKey + " must be a row or a column" + D.where);
    if (model == Distortion::Unknown) {
      if (D.data.size() == 4)
        fail(dKey +
             " has 4 values, which mean Kannala-Brandt (cv::fisheye) or k1 k2 p1 p2 (cv::calibrateCamera): "
             "add distortion_model: fisheye or distortion_model: radtan");
      model = Distortion::Radtan;  // only the pinhole model has 5, 8, 12 or 14
    }
    Camera cam;
    cam.width = width;
    cam.height = height;
    cam.params = pinhole(K, kKey);
    if (model == Distortion::Fisheye) {
      if (D.data.size() != 4)
        fail(dKey + " has " + std::to_string(D.data.size()) + " values but distortion_model fisheye needs 4 (k1..k4)" +
             D.where);
      cam.model = CameraModel::KannalaBrandt4;
      cam.params.insert(cam.params.end(), D.data.begin(), D.data.end());
    } else {
      cam.model = CameraModel::PinholeRadtan;
      const std::vector<double> d = radtan(D, dKey);
      cam.params.insert(cam.params.end(), d.begin(), d.end());
    }
    return cam;
  }

  Eigen::Matrix3d rotation() const {
    const CvValue R = matrix("R", "",
                             " (the rotation from camera 1 to camera 2, X2 = R X1 + T; OpenCV's stereo_calib "
                             "sample writes R and T to extrinsics.yml: merge it into this file)");
    if (R.data.size() == 3) return rodrigues(R.data);
    if (R.rows != 3 || R.cols != 3)
      fail("R must be a 3x3 rotation matrix or a 3-vector (Rodrigues, as cv::Rodrigues)" + R.where);
    Eigen::Matrix3d out;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out(r, c) = R.data[size_t(3 * r + c)];
    return out;
  }

  // OpenCV's 3-value form of a rotation: axis * angle.
  static Eigen::Matrix3d rodrigues(const std::vector<double>& r) {
    const Eigen::Vector3d v(r[0], r[1], r[2]);
    const double angle = v.norm();
    if (!(angle > 0)) return Eigen::Matrix3d::Identity();
    return Eigen::AngleAxisd(angle, v / angle).toRotationMatrix();
  }

  Eigen::Vector3d translation() const {
    const CvValue T = matrix("T", "", " (the translation, X2 = R X1 + T)");
    if (T.data.size() != 3) fail("T must hold 3 values" + T.where);
    return {T.data[0], T.data[1], T.data[2]};
  }
};

// ------------------------------------------------------------------------------------------
// Writing.

struct CvMatrix {
  std::string key;
  int rows, cols;
  std::vector<double> data;
};

// fisheye for two Kannala-Brandt cameras, plumb_bob for two radtan ones; the other models
// have no standard OpenCV stereo form.
const char* distortionName(const Rig& rig, const std::string& path) {
  for (const Camera* cam : {&rig.cam0, &rig.cam1})
    if (cam->model != CameraModel::KannalaBrandt4 && cam->model != CameraModel::PinholeRadtan)
      throw Error(path + ": OpenCV calibration files cannot represent the " + cam->modelName() +
                  " camera model (only fisheye = Kannala-Brandt 4 and pinhole radtan): write Kalibr or Basalt instead");
  if (rig.cam0.model != rig.cam1.model)
    throw Error(path + ": OpenCV stereo files have one distortion_model for both cameras, but cam0 is " +
                rig.cam0.modelName() + " and cam1 " + rig.cam1.modelName());
  if (rig.cam0.width != rig.cam1.width || rig.cam0.height != rig.cam1.height)
    throw Error(path + ": OpenCV stereo files have one image size, but the cameras differ in resolution");
  return rig.cam0.model == CameraModel::KannalaBrandt4 ? "fisheye" : "plumb_bob";
}

std::vector<CvMatrix> matrices(const Rig& rig) {
  std::vector<CvMatrix> out;
  for (int i = 0; i < 2; ++i) {
    const Camera& cam = i ? rig.cam1 : rig.cam0;
    const std::vector<double>& p = cam.params;
    const std::string n = std::to_string(i + 1);
    out.push_back({"K" + n, 3, 3, {p[0], 0, p[2], 0, p[1], p[3], 0, 0, 1}});
    // The shapes OpenCV returns: 4x1 from cv::fisheye, 1x5 (k1 k2 p1 p2 k3) from calib3d.
    if (cam.model == CameraModel::KannalaBrandt4) {
      out.push_back({"D" + n, 4, 1, {p[4], p[5], p[6], p[7]}});
    } else {
      out.push_back({"D" + n, 1, 5, {p[4], p[5], p[6], p[7], 0}});
    }
  }
  const Eigen::Matrix3d& R = rig.R;
  out.push_back({"R", 3, 3, {R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)}});
  out.push_back({"T", 3, 1, {rig.t.x(), rig.t.y(), rig.t.z()}});
  return out;
}

std::string values(const std::vector<double>& data, const char* separator) {
  std::string out;
  for (size_t i = 0; i < data.size(); ++i) out += (i ? separator : "") + exactNumber(data[i]);
  return out;
}

std::string yamlText(const Rig& rig, const char* model) {
  std::ostringstream os;
  os << "%YAML:1.0\n---\n"
     << "image_width: " << rig.cam0.width << "\nimage_height: " << rig.cam0.height << "\n"
     << "distortion_model: " << model << "\n";
  for (const CvMatrix& m : matrices(rig))
    os << m.key << ": !!opencv-matrix\n   rows: " << m.rows << "\n   cols: " << m.cols << "\n   dt: d\n"
       << "   data: [ " << values(m.data, ", ") << " ]\n";
  return os.str();
}

std::string xmlText(const Rig& rig, const char* model) {
  std::ostringstream os;
  os << "<?xml version=\"1.0\"?>\n<opencv_storage>\n"
     << "<image_width>" << rig.cam0.width << "</image_width>\n<image_height>" << rig.cam0.height
     << "</image_height>\n<distortion_model>" << calib::xmlEscape(model) << "</distortion_model>\n";
  for (const CvMatrix& m : matrices(rig))
    os << "<" << m.key << " type_id=\"opencv-matrix\">\n  <rows>" << m.rows << "</rows>\n  <cols>" << m.cols
       << "</cols>\n  <dt>d</dt>\n  <data>\n    " << values(m.data, " ") << "</data></" << m.key << ">\n";
  os << "</opencv_storage>\n";
  return os.str();
}

bool endsWithXml(const std::string& path) { return path.size() >= 4 && lower(path.substr(path.size() - 4)) == ".xml"; }

Rig readOpenCv(const std::string& text, const std::string& name, const CalibHints& hints) {
  const CvStorage storage = calib::firstSignificantChar(text) == '<' ? calib::parseOpenCvXml(text, name)
                                                                     : storageFromYaml(YamlDoc(name), text);
  return OpenCvRigReader(name, storage, hints).read();
}

}  // namespace

Rig parseOpenCv(const std::string& text, const std::string& name, const CalibHints& hints) {
  return readOpenCv(text, name, hints);
}

Rig loadOpenCv(const std::string& path, const CalibHints& hints) {
  return readOpenCv(calib::readTextFile(path), path, hints);
}

void saveOpenCv(const Rig& rig, const std::string& path) {
  calib::checkRigBeforeSaving(rig, path);
  const char* model = distortionName(rig, path);
  calib::writeTextFile(path, endsWithXml(path) ? xmlText(rig, model) : yamlText(rig, model));
}

}  // namespace cs

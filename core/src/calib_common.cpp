// Shared helpers of the calibration readers and writers (see calib_common.hpp).
#include "calib_common.hpp"

#include <Eigen/LU>  // determinant()
#include <Eigen/SVD>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <locale>
#include <sstream>

namespace cs::calib {

std::string formatNumber(double v, int precision) {
  std::ostringstream os;
  os.imbue(std::locale::classic());
  os.precision(precision);
  os << v;
  return os.str();
}

std::string exactNumber(double v) {
  for (int precision = 1; precision < 17; ++precision) {
    const std::string text = formatNumber(v, precision);
    std::istringstream is(text);
    is.imbue(std::locale::classic());
    double back = 0;
    if (is >> back && back == v) return text;
  }
  return formatNumber(v, 17);
}

std::string numberList(const std::vector<double>& v) {
  std::string out = "[";
  for (size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + exactNumber(v[i]);
  return out + "]";
}

std::string oneLine(std::string text) {
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  return text;
}

std::string readTextFile(const std::string& path) {
  if (!std::filesystem::exists(path)) throw Error(oneLine(path + ": cannot open file (it does not exist)"));
  if (std::filesystem::is_directory(path)) throw Error(oneLine(path + ": cannot open file (it is a directory)"));
  std::ifstream file(path, std::ios::binary);
  if (!file) throw Error(oneLine(path + ": cannot open file"));
  std::ostringstream text;
  text << file.rdbuf();
  if (file.bad()) throw Error(oneLine(path + ": error while reading"));
  return text.str();
}

void writeTextFile(const std::string& path, const std::string& text) {
  std::ofstream file(path, std::ios::binary);
  if (!file) throw Error(path + ": cannot open file for writing");
  file << text;
  if (!file.flush()) throw Error(path + ": error while writing");
}

namespace {

// A rotation is one to this: what a double written with 10 or more significant digits keeps.
constexpr double kRotationTolerance = 1e-6;

double orthonormalityError(const Eigen::Matrix3d& R) {
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
}

}  // namespace

void checkPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const std::string& poseName) {
  if (!R.allFinite() || !t.allFinite()) throw Error(poseName + " has non-finite entries");
  const double det = R.determinant();
  const double orthoError = orthonormalityError(R);
  if (std::abs(det - 1.0) > kRotationTolerance || orthoError > kRotationTolerance)
    throw Error(poseName + " rotation is not a rotation (det=" + formatNumber(det, 10) +
                ", |R^T R - I|=" + formatNumber(orthoError, 3) + ")");
  // Depth from stereo needs a baseline; a zero t is usually a missing or mis-read pose.
  if (t.norm() < 1e-6) throw Error("zero baseline (|t| = " + formatNumber(t.norm(), 3) + " m in " + poseName + ")");
}

void checkCamera(const Camera& cam, const std::string& name) {
  try {
    cam.validate();
  } catch (const Error& e) {
    throw Error(name + ": " + e.what());
  }
}

// Files print rotations to a few significant digits (ORB-SLAM3's T265 example: 6, as float,
// |R^T R - I| = 1e-6): a rotation within a thousandth of orthonormal is a rotation written
// coarsely and becomes the nearest exact one; anything farther is a wrong matrix.
constexpr double kPrintedRotationTolerance = 1e-3;

void checkRig(Rig& rig, const std::string& file, const std::string& poseName) {
  try {
    checkCamera(rig.cam0, "cam0");
    checkCamera(rig.cam1, "cam1");
    const double orthoError = orthonormalityError(rig.R);
    // Only where the strict check would refuse it: a rotation read exactly stays bit for bit.
    if (rig.R.allFinite() && rig.R.determinant() > 0 && orthoError > kRotationTolerance &&
        orthoError <= kPrintedRotationTolerance) {
      const Eigen::JacobiSVD<Eigen::Matrix3d> svd(rig.R, Eigen::ComputeFullU | Eigen::ComputeFullV);
      rig.R = svd.matrixU() * svd.matrixV().transpose();
    }
    checkPose(rig.R, rig.t, poseName);
  } catch (const Error& e) {
    throw Error(oneLine(file + ": " + e.what()));
  }
}

void checkCameraRig(const CameraRig& rig, const std::string& file) {
  try {
    rig.validate();
  } catch (const Error& e) {
    throw Error(oneLine(file + ": " + e.what()));
  }
}

void checkRigBeforeSaving(const Rig& rig, const std::string& path) {
  try {
    rig.validate();
  } catch (const Error& e) {
    throw Error(path + ": not saving an invalid rig: " + e.what());
  }
}

char firstSignificantChar(const std::string& text) {
  size_t i = text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  for (; i < text.size(); ++i)
    if (!std::isspace(static_cast<unsigned char>(text[i]))) return text[i];
  return 0;
}

// ------------------------------------------------------------------------------------------
// YamlDoc

void YamlDoc::fail(const std::string& problem) const { throw Error(oneLine(name_ + ": " + problem)); }

namespace {

bool isKeyChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-'; }

// OpenCV's parser takes "key:value" without a space (ORB-SLAM3 files have
// "Viewer.PointSize:2"); YAML does not. A key at the start of a line directly followed by
// ':' and a value gets the space, which changes nothing else on the line.
std::string withSpaceAfterKeys(const std::string& text) {
  std::string out;
  out.reserve(text.size() + 16);
  size_t i = 0;
  while (i < text.size()) {
    const size_t end = std::min(text.find('\n', i), text.size());
    size_t k = i;
    while (k < end && text[k] == ' ') ++k;
    const size_t keyStart = k;
    while (k < end && isKeyChar(text[k])) ++k;
    const bool glued = k > keyStart && std::isalpha(static_cast<unsigned char>(text[keyStart])) && k + 1 < end &&
                       text[k] == ':' && text[k + 1] != ' ' && text[k + 1] != '\t' && text[k + 1] != '\r' &&
                       text[k + 1] != ':';
    out.append(text, i, glued ? k + 1 - i : end - i);
    if (glued) out.append(" ").append(text, k + 1, end - k - 1);
    if (end < text.size()) out += '\n';
    i = end + 1;
  }
  return out;
}

// OpenCV writes "%YAML:1.0", which is not a YAML directive; as a comment it keeps the
// line numbers of everything after it. Such a file is OpenCV's, so it is read as leniently
// as OpenCV reads it.
std::string withoutOpenCvDirective(std::string text) {
  if (text.compare(0, 6, "%YAML:") != 0) return text;
  text[0] = '#';
  return withSpaceAfterKeys(text);
}

}  // namespace

YAML::Node YamlDoc::parse(const std::string& text, const char* syntax) const {
  std::string input = withoutOpenCvDirective(text);
  const char first = firstSignificantChar(input);
  if (first == '{' || first == '[')
    for (char& c : input)
      if (c == '\t') c = ' ';
  try {
    return YAML::Load(input);
  } catch (const YAML::ParserException& e) {
    fail(std::string(syntax) + " syntax error at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  } catch (const YAML::Exception& e) {
    fail(std::string(syntax) + " error: " + e.what());
  }
}

std::string YamlDoc::lineOf(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? std::string() : " (line " + std::to_string(mark.line + 1) + ")";
}

YAML::Node YamlDoc::find(const YAML::Node& parent, const std::string& key) {
  if (!parent.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  const YAML::Node& p = parent;  // the const operator[] does not insert the key
  return p[key];
}

YAML::Node YamlDoc::require(const YAML::Node& parent, const std::string& key, const std::string& prefix) const {
  const YAML::Node node = find(parent, key);
  if (!node.IsDefined()) fail("missing key \"" + dotted(prefix, key) + "\"");
  return node;
}

double YamlDoc::number(const YAML::Node& node, const std::string& key) const {
  if (!node.IsScalar()) fail(key + " is not a number" + lineOf(node));
  try {
    return node.as<double>();
  } catch (const YAML::Exception&) {
    fail(key + " is not a number ('" + node.Scalar() + "')" + lineOf(node));
  }
}

std::vector<double> YamlDoc::numbers(const YAML::Node& node, const std::string& key) const {
  if (!node.IsSequence()) fail(key + " must be a list of numbers" + lineOf(node));
  std::vector<double> out;
  for (size_t i = 0; i < node.size(); ++i) out.push_back(number(node[i], key + "[" + std::to_string(i) + "]"));
  return out;
}

std::string YamlDoc::text(const YAML::Node& node, const std::string& key) const {
  if (!node.IsScalar()) fail(key + " must be a string" + lineOf(node));
  return node.Scalar();
}

int YamlDoc::integer(const YAML::Node& node, const std::string& key, int lo, int hi) const {
  const double v = number(node, key);
  if (v != std::floor(v) || v < lo || v > hi)
    fail(key + " must be a whole number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
         formatNumber(v) + lineOf(node));
  return int(v);
}

Eigen::Matrix4d YamlDoc::transform(const YAML::Node& node, const std::string& key) const {
  const bool matrix = node.IsMap();
  const std::vector<double> data = numbers(matrix ? require(node, "data", key) : node, matrix ? key + ".data" : key);
  if (matrix) {
    const int rows = integer(require(node, "rows", key), key + ".rows", 1, 4);
    const int cols = integer(require(node, "cols", key), key + ".cols", 1, 4);
    if (cols != 4 || (rows != 3 && rows != 4) || data.size() != size_t(rows * cols))
      fail(key + " must be a 4x4 or 3x4 matrix with rows * cols values" + lineOf(node));
  }
  if (data.size() != 16 && data.size() != 12) fail(key + " must be a 4x4 or 3x4 matrix" + lineOf(node));
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  for (size_t i = 0; i < data.size(); ++i) T(int(i / 4), int(i % 4)) = data[i];
  if ((T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9)
    fail(key + " last row must be [0, 0, 0, 1]" + lineOf(node));
  return T;
}

Eigen::Matrix4d rigidInverse(const Eigen::Matrix4d& T) {
  Eigen::Matrix4d out = Eigen::Matrix4d::Identity();
  out.topLeftCorner<3, 3>() = T.topLeftCorner<3, 3>().transpose();
  out.topRightCorner<3, 1>() = -T.topLeftCorner<3, 3>().transpose() * T.topRightCorner<3, 1>();
  return out;
}

}  // namespace cs::calib

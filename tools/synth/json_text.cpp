// Text writers for the synthetic data sets' meta files (json_text.hpp).
#include "synth/json_text.hpp"

#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "curvestereo/image.hpp"

namespace cs::synth::json {

std::string num(double v) {
  char text[64];
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(text, sizeof text, "%.*g", precision, v);
    if (std::strtod(text, nullptr) == v) break;
  }
  return text;
}

std::string list(const std::vector<double>& values) {
  std::string s = "[";
  for (size_t i = 0; i < values.size(); ++i) s += (i ? ", " : "") + num(values[i]);
  return s + "]";
}

std::string vec(const Eigen::Vector3d& v) { return list({v.x(), v.y(), v.z()}); }

std::string matrix4(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  std::string s = "[";
  for (int r = 0; r < 3; ++r) s += list({R(r, 0), R(r, 1), R(r, 2), t(r)}) + ", ";
  return s + "[0, 0, 0, 1]]";
}

void writeText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw Error("cannot write '" + path.string() + "'");
}

}  // namespace cs::synth::json

// The small JSON / text writers that the synthetic data sets' meta files share
// (sequence_writer.cpp's meta.json, rig.cpp's rig.json).
#pragma once
#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

namespace cs::synth::json {

// Shortest text that reads back as the same double ("0.1", "2.942900057068167"); the
// program never changes the C locale, so the decimal point is '.'.
std::string num(double v);
// [a, b, c] of num()s.
std::string list(const std::vector<double>& values);
std::string vec(const Eigen::Vector3d& v);
// A 4 x 4 rigid transform [R t; 0 0 0 1] as JSON rows.
std::string matrix4(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);
// Throws cs::Error naming the file when it cannot be written.
void writeText(const std::filesystem::path& path, const std::string& text);

}  // namespace cs::synth::json

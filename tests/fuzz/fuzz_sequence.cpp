// libFuzzer target: the sequence text readers, cs::parseAslCsv (an ASL camera's data.csv)
// and cs::parsePoses (a poses file, CSV or TUM), both on every input. Each must return or
// throw a one-line cs::Error; a result that breaks its promises is a finding too.
#include <cstdint>
#include <string>

#include "curvestereo/sequence.hpp"

namespace {

void checkMessage(const cs::Error& e) {
  if (std::string(e.what()).find('\n') != std::string::npos) __builtin_trap();  // messages are one line
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto rows = cs::parseAslCsv(text, "data.csv");
    for (size_t i = 0; i < rows.size(); ++i) {
      if (rows[i].filename.empty() || rows[i].timestampNs < 0) __builtin_trap();
      if (i && rows[i].timestampNs <= rows[i - 1].timestampNs) __builtin_trap();  // sorted, unique
    }
  } catch (const cs::Error& e) {
    checkMessage(e);
  }
  try {
    for (const auto& [t, pose] : cs::parsePoses(text, "poses")) {
      if (t < 0 || !pose.t.allFinite() || !pose.R.allFinite()) __builtin_trap();
      // A rotation: R^T R = I (the quaternion was normalised).
      if (((pose.R.transpose() * pose.R) - Eigen::Matrix3d::Identity()).norm() > 1e-6) __builtin_trap();
    }
  } catch (const cs::Error& e) {
    checkMessage(e);
  }
  return 0;
}

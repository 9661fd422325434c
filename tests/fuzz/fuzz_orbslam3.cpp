// libFuzzer target: the ORB-SLAM3 settings reader (parseOrbSlam3), with OpenCV's lenient
// "key:value" in front of YAML, without the format detection. See fuzz_calib_check.hpp.
#include "fuzz_calib_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto parse = [](const std::string& text, cs::CalibFormat& format) {
    format = cs::CalibFormat::OrbSlam3;
    return cs::parseOrbSlam3(text, "fuzz.yaml");
  };
  return cs::fuzz::fuzzCalibration(data, size, parse);
}

// libFuzzer target: the OpenCV FileStorage reader (parseOpenCv), YAML and XML alike,
// without the format detection in front of it. See fuzz_calib_check.hpp.
#include "fuzz_calib_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto parse = [](const std::string& text, cs::CalibFormat& format) {
    format = cs::CalibFormat::OpenCv;
    return cs::parseOpenCv(text, "fuzz.yml");
  };
  return cs::fuzz::fuzzCalibration(data, size, parse);
}

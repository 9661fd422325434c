// libFuzzer target: the Basalt calibration.json reader (parseBasalt) without the format
// detection in front of it. See fuzz_calib_check.hpp.
#include "fuzz_calib_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto parse = [](const std::string& text, cs::CalibFormat& format) {
    format = cs::CalibFormat::Basalt;
    return cs::parseBasalt(text, "fuzz.json");
  };
  return cs::fuzz::fuzzCalibration(data, size, parse);
}

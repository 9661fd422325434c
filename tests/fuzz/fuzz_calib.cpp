// libFuzzer target: parseCalibration (the format chosen from the content, then the Kalibr,
// Basalt or OpenCV reader), as loadCalibration and the CLI's --calib use it. See
// fuzz_calib_check.hpp for what counts as a finding.
#include "fuzz_calib_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto parse = [](const std::string& text, cs::CalibFormat& format) {
    return cs::parseCalibration(text, "fuzz.calib", &format);
  };
  return cs::fuzz::fuzzCalibration(data, size, parse);
}

// libFuzzer target: the VINS-Fusion config reader and the camodocal camera reader it calls
// (parseVinsFusion), the input split as fuzz_vins.hpp says. See fuzz_calib_check.hpp.
#include "fuzz_vins.hpp"
#include "fuzz_calib_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto parse = [](const std::string& text, cs::CalibFormat& format) {
    format = cs::CalibFormat::VinsFusion;
    return cs::fuzz::parseVinsInput(text);
  };
  return cs::fuzz::fuzzCalibration(data, size, parse);
}

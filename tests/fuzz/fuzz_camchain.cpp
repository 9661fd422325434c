// libFuzzer target: the Kalibr camchain parser. Any input must give a Rig that passes
// validate() or a one-line cs::Error; anything else (another exception, a crash, a
// sanitizer report) is a finding. A rig that loads is exercised a little further.
#include <cstdint>
#include <string>

#include "curvestereo/params.hpp"
#include "fuzz_calib_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  cs::Rig rig;
  try {
    rig = cs::parseKalibr(text, "fuzz.yaml");
  } catch (const cs::Error& e) {
    cs::fuzz::requireOneLine(e);
    return 0;
  }
  cs::fuzz::exerciseCameras(rig);
  (void)cs::pyramidPlan(rig.cam0.width, rig.cam0.height, cs::Params());
  return 0;
}

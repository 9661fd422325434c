// libFuzzer target: a rig of N cameras from any calibration format (parseCameraRig: Kalibr
// chains, Basalt N-camera files, the pair formats). Any input must give a rig that passes
// validate() or a one-line cs::Error; anything else (another exception, a crash, a sanitizer
// report) is a finding. A rig that loads must give every pair, its overlap and a pair choice.
#include <cstdint>
#include <string>

#include "curvestereo/camera_rig.hpp"
#include "fuzz_calib_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  cs::CameraRig rig;
  try {
    rig = cs::parseCameraRig(text, "fuzz.yaml");
  } catch (const cs::Error& e) {
    cs::fuzz::requireOneLine(e);
    return 0;
  }
  rig.validate();  // a rig that loads is valid: a throw here is a finding
  for (int i = 0; i < rig.size(); ++i)
    for (int j = 0; j < rig.size(); ++j)
      if (i != j) cs::fuzz::exerciseCameras(cs::pairRig(rig, i, j));
  if (cs::choosePairs(rig).empty()) __builtin_trap();  // every camera overlaps another
  return 0;
}

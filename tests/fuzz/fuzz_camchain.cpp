// libFuzzer target: the Kalibr camchain parser. Any input must give a Rig that passes
// validate() or a one-line cs::Error; anything else (another exception, a crash, a
// sanitizer report) is a finding. A rig that loads is exercised a little further.
#include <cstdint>
#include <string>

#include "curvestereo/camera_models.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/rig.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  cs::Rig rig;
  try {
    rig = cs::parseKalibr(text, "fuzz.yaml");
  } catch (const cs::Error& e) {
    if (std::string(e.what()).find('\n') != std::string::npos) __builtin_trap();  // messages are one line
    return 0;
  }
  // A rig that loads must be usable: the camera models may not misbehave on it.
  for (const cs::Camera* cam : {&rig.cam0, &rig.cam1}) {
    const double w = cam->width, h = cam->height;
    for (const cs::Vec2<double>& px : {cs::Vec2<double>(0, 0), cs::Vec2<double>(w - 1, h - 1),
                                       cs::Vec2<double>(0.5 * (w - 1), 0.5 * (h - 1)), cs::Vec2<double>(w - 1, 0)}) {
      cs::Vec3<double> ray;
      if (!cam->unproject(px, ray)) continue;
      cs::Vec2<double> back;
      cs::Mat23<double> J;
      (void)cam->project(ray, back, &J);
    }
    (void)cam->maxAngle();
    (void)cam->scaled(0.5);
  }
  (void)cs::pyramidPlan(rig.cam0.width, rig.cam0.height, cs::Params());
  return 0;
}

#include "camera_options.hpp"

#include <filesystem>
#include <fstream>

#include "curvestereo/image_io.hpp"

namespace cs::cli {

const std::set<std::string> kCameraOptions = {"camera",         "exposure",      "vignette",     "vignette-left",
                                              "vignette-right", "vignette-mode", "gain-left",    "gain-right",
                                              "offset-left",    "offset-right",  "camera-gamma", "blur",
                                              "shot",           "read",          "bits",         "noise-seed"};

synth::CameraPhotometry cameraModelFromArgs(const Args& args, uint32_t defaultSeed) {
  synth::CameraPhotometry m = synth::photometryProfile(args.get("camera", "none"));
  m.seed = defaultSeed;
  bool overridden = false;
  auto number = [&](const char* name, double& field) {
    if (!args.has(name)) return;
    field = args.getDouble(name, field);  // refuses words, NaN and infinities
    overridden = true;
  };
  number("exposure", m.exposure);
  number("vignette", m.left.rim);
  if (args.has("vignette")) m.right.rim = m.left.rim;
  number("vignette-left", m.left.rim);  // after --vignette: the specific one wins
  number("vignette-right", m.right.rim);
  number("gain-left", m.left.gain);
  number("gain-right", m.right.gain);
  number("offset-left", m.left.offset);
  number("offset-right", m.right.offset);
  number("camera-gamma", m.gamma);
  number("blur", m.blur);
  number("shot", m.shot);
  number("read", m.read);
  if (args.has("vignette-mode")) m.vignetteMode = synth::parseVignetteMode(args.get("vignette-mode", "radius"));
  if (args.has("bits")) m.bits = args.getInt("bits", m.bits);
  overridden = overridden || args.has("vignette-mode") || args.has("bits");
  if (args.has("noise-seed")) {
    const int seed = args.getInt("noise-seed", 0);
    if (seed < 0) throw Error("option --noise-seed expects a non-negative integer");
    m.seed = uint32_t(seed);
  }
  // The name says where the values came from; photometry.json lists them all.
  if (overridden) m.profile = m.profile == "none" ? "custom" : m.profile + "+overrides";
  m.validate();
  return m;
}

void writePhotometryJson(const synth::CameraPhotometry& model, double exposureScale, const std::string& dir) {
  const std::string file = (std::filesystem::path(dir) / "photometry.json").string();
  std::ofstream out(file, std::ios::binary);
  out << model.json(exposureScale);
  if (!out) throw Error("cannot write '" + file + "'");
}

void writePairImage(const std::string& path, const ImageF& image, const synth::CameraPhotometry& model) {
  if (model.enabled() && model.bits == 16)
    writePngGray16(path, image);
  else
    writePngGray(path, image);
}

}  // namespace cs::cli

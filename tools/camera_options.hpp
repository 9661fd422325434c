// The camera-model options of `synth` and `demo`: --camera none|t265 plus per-field
// overrides, turned into a synth::CameraPhotometry (tools/synth/photometry.hpp).
#pragma once
#include <cstdint>
#include <set>
#include <string>

#include "args.hpp"
#include "synth/photometry.hpp"

namespace cs::cli {

// Every camera-model option name (for allowOnly()).
extern const std::set<std::string> kCameraOptions;

// The model the options ask for: the --camera profile (default none), then each
// override given; the noise seed defaults to defaultSeed (the scene's seed). Checked:
// a bad value is a one-line cs::Error naming the option.
synth::CameraPhotometry cameraModelFromArgs(const Args& args, uint32_t defaultSeed);

// Writes model.json(exposureScale) to dir/photometry.json.
void writePhotometryJson(const synth::CameraPhotometry& model, double exposureScale, const std::string& dir);

// writePngGray16 when the model asks for 16 bits, else writePngGray (8 bits, as without a model).
void writePairImage(const std::string& path, const ImageF& image, const synth::CameraPhotometry& model);

}  // namespace cs::cli

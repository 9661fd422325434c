// A camera (photometric) model for synthetic pairs: what a small, low-cost fisheye
// camera such as the RealSense T265 does to the clean radiance the ray caster renders.
// Clean synthetic pairs are bright, noise-free and identical in gain left and right;
// real ones are dark, vignetted, noisy and a few percent apart in gain, and a method
// tuned only on the clean ones can fail on the real ones. This model closes that gap
// so tests and users can render pairs that look like the camera.
//
// The stages, in the order light meets them (each off at its identity value):
//   1. vignetting (lens):  v = max(0, 1 - (1 - rim) * s^2), per camera, where s is
//        radius mode: distance from the principal point / half the smaller image side
//        angle mode:  angle of the pixel's ray off the optical axis / 90 deg
//      (the same for the default equidistant 180 deg synth lens; angle mode follows
//      the lens for other models);
//   2. optics blur: Gaussian, sigma `blur` px (borders replicated);
//   3. exposure: one scale for both cameras (they share an exposure time) that puts
//      the median of the left image inside its valid region at `exposure`, before the
//      per-camera gain and offset;
//   4. per camera: I * gain + offset (analogue gain, black level);
//   5. sensor noise: Gaussian, variance shot * I + read^2, with I and the variance in
//      8-bit grey levels (0..255) whatever the output bit depth, so one setting means
//      the same noise at 8 and 16 bits; I is clamped at 0 for the variance;
//   6. clamp to [0, 1] (saturation), then the response curve I^(1 / gamma) (gamma > 1
//      brightens the shadows like a display encoding; 1 = linear, as the T265 is);
//   7. quantisation to `bits` (8 or 16): multiples of 1 / (2^bits - 1).
// Noise covers the whole sensor, including the dark corners outside the image circle.
// Depth (the ground truth) is never touched. Everything is deterministic per seed on
// every platform (raw mt19937 bits, arithmetic written out, one thread).
#pragma once
#include <cstdint>
#include <string>

#include "curvestereo/camera.hpp"
#include "curvestereo/image.hpp"
#include "synth/scene.hpp"

namespace cs::synth {

enum class VignetteMode { Radius, Angle };

// What differs between the two cameras of the rig.
struct CameraResponse {
  double rim = 1.0;     // vignetting: brightness at s = 1 relative to the centre, (0, 1]
  double gain = 1.0;    // multiplies the exposed signal, (0, 10]
  double offset = 0.0;  // added after the gain (black level), grey in [-1, 1]
};

struct CameraPhotometry {
  std::string profile = "none";  // the name this model came from (reported only)
  double exposure = 0.0;         // target median grey in (0, 1]; 0 leaves the exposure alone
  VignetteMode vignetteMode = VignetteMode::Radius;
  CameraResponse left, right;
  double gamma = 1.0;  // response curve I^(1/gamma), (0, 10]
  double blur = 0.0;   // optics blur sigma, px, [0, 20]
  double shot = 0.0;   // noise variance per 8-bit grey level of signal, >= 0
  double read = 0.0;   // noise standard deviation at zero signal, 8-bit grey levels, >= 0
  int bits = 8;        // output bit depth: 8 or 16
  uint32_t seed = 1;   // noise seed

  // False for the identity model: then applyPhotometry changes nothing at all.
  bool enabled() const;
  // Throws cs::Error with one line naming the first bad field.
  void validate() const;
  // The parameters as a JSON object (the photometry.json written beside a pair).
  std::string json(double exposureScale) const;
};

// "none" (identity) or "t265" (mid-range values of a RealSense T265); throws cs::Error
// for an unknown name.
CameraPhotometry photometryProfile(const std::string& name);
// "radius" | "angle"; throws cs::Error otherwise.
VignetteMode parseVignetteMode(const std::string& name);
const char* vignetteModeName(VignetteMode mode);
// One line for the command output: "t265: exposure median 0.2 (x 3.1), vignette ...".
std::string describePhotometry(const CameraPhotometry& model, double exposureScale);

// Vignetting factor v in [0, 1] of every pixel of one camera.
ImageF vignetting(const Camera& camera, double rim, VignetteMode mode);

// Passes the pair's images through the model (validated first); returns the exposure
// scale used (1 when exposure is 0). Valid pixels are those with depth > 0. The depth
// images are not changed. A disabled model leaves the pair untouched and returns 1.
// fixedScale > 0 is used as the exposure scale instead of the one model.exposure would
// set from this pair's median (a sequence keeps its first frame's, like a fixed exposure).
double applyPhotometry(const CameraPhotometry& model, SynthPair& pair, double fixedScale = 0.0);

}  // namespace cs::synth

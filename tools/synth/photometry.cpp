// The camera (photometric) model of photometry.hpp: vignetting, optics blur, exposure,
// gain and offset, sensor noise, response curve, quantisation.
#include "synth/photometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "synth/random.hpp"

namespace cs::synth {
namespace {

// Validation: !(lo <= v && v <= hi) is also true for NaN, so NaN is always refused.
void checkRange(double v, double lo, double hi, bool openLow, const std::string& what) {
  const bool low = openLow ? v > lo : v >= lo;
  if (!(low && v <= hi && std::isfinite(v))) {
    char text[160];
    std::snprintf(text, sizeof text, "camera model: %s must be in %s%g, %g], got %g", what.c_str(), openLow ? "(" : "[",
                  lo, hi, v);
    throw Error(text);
  }
}

void checkResponse(const CameraResponse& r, const std::string& side) {
  checkRange(r.rim, 0.0, 1.0, true, "the " + side + " vignette rim (--vignette, --vignette-" + side + ")");
  checkRange(r.gain, 0.0, 10.0, true, "the " + side + " gain (--gain-" + side + ")");
  checkRange(r.offset, -1.0, 1.0, false, "the " + side + " offset (--offset-" + side + ")");
}

bool isIdentity(const CameraResponse& r) { return r.rim == 1.0 && r.gain == 1.0 && r.offset == 0.0; }

// Normalised distance of every pixel from the principal point (radius mode): 1 at half
// the smaller image side, where the default fisheye's 180 deg circle ends.
double radiusAt(const Camera& camera, int x, int y) {
  const double cx = camera.params.at(2), cy = camera.params.at(3);
  const double half = 0.5 * std::min(camera.width, camera.height);
  return std::hypot(x - cx, y - cy) / half;
}

// Angle of the pixel's ray off the optical axis / 90 deg (angle mode). Pixels the model
// cannot unproject receive no light: a large value, so the factor clamps to 0.
double angleAt(const BuiltCamera& camera, int x, int y) {
  Vec3<double> ray;
  if (!camera.unproject(Vec2<double>(x, y), ray) || !ray.allFinite()) return 1e3;
  const double cosine = std::clamp(ray.normalized().z(), -1.0, 1.0);
  return std::acos(cosine) / (0.5 * M_PI);
}

// 1-D Gaussian taps for sigma px, radius ceil(3 sigma), normalised to sum 1.
std::vector<double> gaussianTaps(double sigma) {
  const int radius = std::max(1, int(std::ceil(3.0 * sigma)));
  std::vector<double> taps(2 * radius + 1);
  double sum = 0.0;
  for (int i = -radius; i <= radius; ++i) sum += taps[i + radius] = std::exp(-0.5 * (i * i) / (sigma * sigma));
  for (double& t : taps) t /= sum;
  return taps;
}

// One separable pass along x (dx = 1) or y; the border pixel is replicated, as a sensor
// larger than the image would see the same light continue.
ImageF convolve1d(const ImageF& in, const std::vector<double>& taps, bool alongX) {
  const int radius = int(taps.size() / 2);
  ImageF out(in.width, in.height);
  for (int y = 0; y < in.height; ++y)
    for (int x = 0; x < in.width; ++x) {
      double sum = 0.0;
      for (int k = -radius; k <= radius; ++k) {
        const int xs = alongX ? std::clamp(x + k, 0, in.width - 1) : x;
        const int ys = alongX ? y : std::clamp(y + k, 0, in.height - 1);
        sum += taps[k + radius] * in(xs, ys);
      }
      out(x, y) = float(sum);
    }
  return out;
}

ImageF gaussianBlur(const ImageF& in, double sigma) {
  if (sigma <= 0.0) return in;
  const std::vector<double> taps = gaussianTaps(sigma);
  return convolve1d(convolve1d(in, taps, true), taps, false);
}

void multiply(ImageF& image, const ImageF& factor) {
  for (size_t i = 0; i < image.size(); ++i) image.data[i] *= factor.data[i];
}

// Median of the image where depth > 0 (the lower middle for an even count).
double validMedian(const ImageF& image, const ImageF& depth) {
  std::vector<float> values;
  values.reserve(image.size());
  for (size_t i = 0; i < image.size(); ++i)
    if (depth.data[i] > 0.f) values.push_back(image.data[i]);
  if (values.empty()) return 0.0;
  auto middle = values.begin() + (values.size() - 1) / 2;
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// Standard normal draws from raw engine bits (Box-Muller, both outputs used): the
// std:: distributions differ between standard libraries, the noise must not.
class Gaussian {
 public:
  explicit Gaussian(uint32_t seed) : random_(seed) {}
  double operator()() {
    if (haveSpare_) {
      haveSpare_ = false;
      return spare_;
    }
    const double u1 = 1.0 - random_.unit();  // (0, 1]: the log stays finite
    const double u2 = random_.unit();
    const double radius = std::sqrt(-2.0 * std::log(u1));
    spare_ = radius * std::sin(2.0 * M_PI * u2);
    haveSpare_ = true;
    return radius * std::cos(2.0 * M_PI * u2);
  }

 private:
  Random random_;
  double spare_ = 0.0;
  bool haveSpare_ = false;
};

// Stages 4-7 for one camera: gain and offset, noise, clamp, response, quantisation.
void sensor(const CameraPhotometry& m, const CameraResponse& r, double exposureScale, uint32_t seed, ImageF& image) {
  Gaussian normal(seed);
  const bool noisy = m.shot > 0.0 || m.read > 0.0;
  const double levels = m.bits == 16 ? 65535.0 : 255.0;
  for (float& value : image.data) {
    double v = value * exposureScale * r.gain + r.offset;
    if (noisy) {
      const double grey = std::max(0.0, 255.0 * v);  // the signal in 8-bit grey levels
      v += std::sqrt(m.shot * grey + m.read * m.read) / 255.0 * normal();
    }
    v = std::clamp(v, 0.0, 1.0);
    if (m.gamma != 1.0) v = std::pow(v, 1.0 / m.gamma);
    value = float(std::round(v * levels) / levels);
  }
}

// Numbers for photometry.json (enough digits to reproduce the pair) and for messages.
std::string number(double v, int digits = 10) {
  char text[40];
  std::snprintf(text, sizeof text, "%.*g", digits, v);
  return text;
}

}  // namespace

bool CameraPhotometry::enabled() const {
  return exposure != 0.0 || !isIdentity(left) || !isIdentity(right) || gamma != 1.0 || blur != 0.0 || shot != 0.0 ||
         read != 0.0 || bits != 8;
}

void CameraPhotometry::validate() const {
  if (exposure != 0.0) checkRange(exposure, 0.0, 1.0, true, "the exposure (--exposure, median grey; 0 = off)");
  checkResponse(left, "left");
  checkResponse(right, "right");
  checkRange(gamma, 0.0, 10.0, true, "gamma (--camera-gamma)");
  checkRange(blur, 0.0, 20.0, false, "the blur sigma (--blur, px)");
  checkRange(shot, 0.0, 1e3, false, "the shot noise (--shot, variance per grey level)");
  checkRange(read, 0.0, 255.0, false, "the read noise (--read, grey levels)");
  if (bits != 8 && bits != 16) throw Error("camera model: --bits must be 8 or 16, got " + std::to_string(bits));
}

std::string CameraPhotometry::json(double exposureScale) const {
  auto side = [](const CameraResponse& r) {
    return "{\"rim\": " + number(r.rim) + ", \"gain\": " + number(r.gain) + ", \"offset\": " + number(r.offset) + "}";
  };
  return "{\n  \"profile\": \"" + profile + "\",\n  \"exposure\": " + number(exposure) +
         ",\n  \"exposure_scale\": " + number(exposureScale) + ",\n  \"vignette_mode\": \"" +
         vignetteModeName(vignetteMode) + "\",\n  \"left\": " + side(left) + ",\n  \"right\": " + side(right) +
         ",\n  \"gamma\": " + number(gamma) + ",\n  \"blur\": " + number(blur) + ",\n  \"shot\": " + number(shot) +
         ",\n  \"read\": " + number(read) + ",\n  \"bits\": " + std::to_string(bits) +
         ",\n  \"seed\": " + std::to_string(seed) + ",\n  \"noise_units\": \"8-bit grey levels\"\n}\n";
}

CameraPhotometry photometryProfile(const std::string& name) {
  CameraPhotometry m;
  if (name == "none") return m;
  if (name != "t265") throw Error("unknown camera model '" + name + "' (known: none, t265)");
  // The middle of what the T265 pairs show (../shared/data/synthetic_real): median grey
  // 0.10-0.33, rim 25-45 % of the centre, 1-2 grey levels of noise, gains a few % apart.
  m.profile = name;
  m.exposure = 0.2;
  m.left.rim = m.right.rim = 0.35;
  m.right.gain = 1.06;
  m.blur = 0.6;
  m.shot = 0.08;
  m.read = 1.5;
  m.bits = 8;
  return m;
}

VignetteMode parseVignetteMode(const std::string& name) {
  if (name == "radius") return VignetteMode::Radius;
  if (name == "angle") return VignetteMode::Angle;
  throw Error("unknown vignette mode '" + name + "' (known: radius, angle)");
}

const char* vignetteModeName(VignetteMode mode) { return mode == VignetteMode::Angle ? "angle" : "radius"; }

std::string describePhotometry(const CameraPhotometry& m, double exposureScale) {
  auto brief = [](double v) { return number(v, 4); };
  if (!m.enabled()) return m.profile + ": off (clean images)";
  const std::string exposure = m.exposure > 0.0 ? "median " + brief(m.exposure) : std::string("unchanged");
  return m.profile + ": exposure " + exposure + " (x" + brief(exposureScale) + "), vignette rim " + brief(m.left.rim) +
         "/" + brief(m.right.rim) + " (" + vignetteModeName(m.vignetteMode) + "), gain " + brief(m.left.gain) + "/" +
         brief(m.right.gain) + ", offset " + brief(m.left.offset) + "/" + brief(m.right.offset) + ", gamma " +
         brief(m.gamma) + ", blur " + brief(m.blur) + " px, noise shot " + brief(m.shot) + " read " + brief(m.read) +
         " grey levels, " + std::to_string(m.bits) + " bit, seed " + std::to_string(m.seed);
}

ImageF vignetting(const Camera& camera, double rim, VignetteMode mode) {
  ImageF factor(camera.width, camera.height, 1.f);
  if (rim == 1.0) return factor;
  const BuiltCamera built(camera);
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const double s = mode == VignetteMode::Angle ? angleAt(built, x, y) : radiusAt(camera, x, y);
      factor(x, y) = float(std::max(0.0, 1.0 - (1.0 - rim) * s * s));
    }
  return factor;
}

double applyPhotometry(const CameraPhotometry& model, SynthPair& pair, double fixedScale) {
  if (!model.enabled()) return 1.0;
  model.validate();
  multiply(pair.left, vignetting(pair.rig.cam0, model.left.rim, model.vignetteMode));
  multiply(pair.right, vignetting(pair.rig.cam1, model.right.rim, model.vignetteMode));
  pair.left = gaussianBlur(pair.left, model.blur);
  pair.right = gaussianBlur(pair.right, model.blur);
  double scale = 1.0;
  if (fixedScale > 0.0) {
    scale = fixedScale;
  } else if (model.exposure > 0.0) {
    const double median = validMedian(pair.left, pair.depthLeft);
    if (!(median > 0.0)) throw Error("camera model: cannot set the exposure of a black image");
    scale = model.exposure / median;
  }
  // Two independent noise streams drawn from the one seed.
  Random seeds(model.seed);
  const uint32_t leftSeed = seeds.bits(), rightSeed = seeds.bits();
  sensor(model, model.left, scale, leftSeed, pair.left);
  sensor(model, model.right, scale, rightSeed, pair.right);
  return scale;
}

}  // namespace cs::synth

#include "common.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "curvestereo/image_io.hpp"

namespace cs::cli {

const std::set<std::string> kSolverOptions = {
    "preset",    "warps",      "iterations",  "levels",        "lambda",      "du-max",  "alpha0",  "alpha1",
    "max-fov",   "gamma",      "median",      "backend",       "mask",        "epipole", "beta",    "eta",
    "device",    "init",       "init-level",  "init-parallax", "init-radius", "init-p1", "init-p2", "occlusion-weight",
    "data-term", "norm-sigma", "noise-level", "init-warps"};

std::string backendFromArgs(const Args& args) {
  std::string backend = args.get("backend", "auto");
  if (args.has("device")) backend += ":" + args.get("device", "");
  return backend;
}

Params paramsFromArgs(const Args& args) {
  Params p = preset(args.get("preset", "default"));
  p.warps = args.getInt("warps", p.warps);
  p.iterations = args.getInt("iterations", p.iterations);
  p.levels = args.getInt("levels", p.levels);
  if (args.has("data-term")) p = p.withDataTerm(parseDataTerm(args.get("data-term", "normalised")));
  p.normSigma = float(args.getDouble("norm-sigma", p.normSigma));
  p.noiseLevel = float(args.getDouble("noise-level", p.noiseLevel));
  p.lambda = float(args.getDouble("lambda", p.lambda));
  p.duMax = float(args.getDouble("du-max", p.duMax));
  p.alpha0 = float(args.getDouble("alpha0", p.alpha0));
  p.alpha1 = float(args.getDouble("alpha1", p.alpha1));
  p.beta = float(args.getDouble("beta", p.beta));
  p.eta = float(args.getDouble("eta", p.eta));
  p.gamma = float(args.getDouble("gamma", p.gamma));
  p.maxFovDeg = args.getDouble("max-fov", p.maxFovDeg);
  p.epipoleDeg = args.getDouble("epipole", p.epipoleDeg);
  if (args.has("init")) p.init = parseInit(args.get("init", "none"));
  p.initLevel = args.getInt("init-level", p.initLevel);
  p.initMaxParallaxDeg = args.getDouble("init-parallax", p.initMaxParallaxDeg);
  p.initRadius = args.getInt("init-radius", p.initRadius);
  p.initP1 = float(args.getDouble("init-p1", p.initP1));
  p.initP2 = float(args.getDouble("init-p2", p.initP2));
  p.occlusionWeight = float(args.getDouble("occlusion-weight", p.occlusionWeight));
  p.initWarps = args.getInt("init-warps", p.initWarps);

  if (args.has("median")) {
    std::string m = args.get("median", "on");
    if (m != "on" && m != "off") throw Error("option --median expects on or off, got '" + m + "'");
    p.medianFilter = m == "on";
  }
  p.validate();
  return p;
}

namespace {

std::string sizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

// "1/2", "3/4", "2": s = num/den in lowest terms, for messages.
std::string ratioText(long long num, long long den) {
  long long a = num, b = den;
  while (b) a %= b, std::swap(a, b);
  num /= a, den /= a;
  return den == 1 ? std::to_string(num) : std::to_string(num) + "/" + std::to_string(den);
}

}  // namespace

ImageF loadImage(const std::string& path, const char* which) {
  PngFormat format;
  ImageF img = readPngGray(path, &format);
  if (format.colour)
    std::fprintf(stderr, "curvestereo: note: %s image '%s' is colour (%d-bit%s); converted to gray (Rec. 601 luma)\n",
                 which, path.c_str(), format.bitDepth, format.alpha ? ", alpha dropped" : "");
  return img;
}

ImageF loadImageFor(const std::string& path, const Camera& cam, const char* which) {
  ImageF img = loadImage(path, which);
  if (img.width != cam.width || img.height != cam.height)
    throw Error(std::string(which) + " image '" + path + "' is " + sizeText(img.width, img.height) +
                " but the calibration is for " + sizeText(cam.width, cam.height));
  return img;
}

StereoInputs loadStereoInputs(const std::string& calib, const std::string& leftPath, const std::string& rightPath,
                              bool scaleIntrinsics) {
  StereoInputs in{loadCalibration(calib), loadImage(leftPath, "left"), loadImage(rightPath, "right")};
  const ImageF &l = in.left, &r = in.right;
  if (l.width != r.width || l.height != r.height)
    throw Error("left image '" + leftPath + "' is " + sizeText(l.width, l.height) + " but right image '" + rightPath +
                "' is " + sizeText(r.width, r.height) + ": the pair must have the same size");
  const Camera cam = in.rig.cam0;  // a copy: the rig's cameras may be replaced below
  if (l.width == cam.width && l.height == cam.height) return in;
  // The same lens at another resolution (e.g. a half-resolution T265 stream) keeps its
  // model; only fx, fy, cx, cy scale. That holds only for a uniform rescale: a crop or a
  // change of aspect ratio needs a new calibration.
  const bool uniform = (long long)l.width * cam.height == (long long)l.height * cam.width;
  const std::string mismatch = "left image '" + leftPath + "' is " + sizeText(l.width, l.height) +
                               " but the calibration '" + calib + "' is for " + sizeText(cam.width, cam.height);
  if (!uniform)
    throw Error(mismatch +
                " (not a uniform rescale, so the intrinsics cannot be scaled: calibrate at this resolution)");
  const std::string ratio = ratioText(l.width, cam.width);
  if (!scaleIntrinsics)
    throw Error(mismatch + " (an exact " + ratio + " rescale: pass --scale-intrinsics to scale the calibration)");
  const double s = double(l.width) / double(cam.width);
  in.rig.cam0 = in.rig.cam0.scaled(s);
  in.rig.cam1 = in.rig.cam1.scaled(s);
  if (in.rig.cam1.width != l.width || in.rig.cam1.height != l.height)
    throw Error("the calibration's cameras differ in resolution; cannot scale it to " + sizeText(l.width, l.height));
  in.rig.validate();
  std::fprintf(stderr, "curvestereo: note: images are %s, calibration %s: intrinsics scaled by %s\n",
               sizeText(l.width, l.height).c_str(), sizeText(cam.width, cam.height).c_str(), ratio.c_str());
  return in;
}

void writeDepthPng(const std::string& path, const ImageF& radialDepth) { writePngRgb(path, depthPicture(radialDepth)); }

float minConfidenceFromArgs(const Args& args, const Params& params) {
  if (!args.has("min-confidence")) return 0.f;
  if (params.init != Params::Init::PlaneSweep)
    throw Error(
        "--min-confidence needs the plane-sweep initialiser's confidence (--init planesweep; on in --preset realtime "
        "and quality)");
  const double c = args.getDouble("min-confidence", 0.0);
  if (!(c >= 0 && c <= 1)) throw Error("--min-confidence must be in [0, 1]");
  return float(c);
}

void writeOutputs(const std::string& dir, const DepthResult& r, const ImageF& left, float minConfidence) {
  std::filesystem::create_directories(dir);
  auto path = [&](const char* name) { return (std::filesystem::path(dir) / name).string(); };
  writeExr(path("depth.exr"), r.depth.radial);
  writeDepthPng(path("depth.png"), r.depth.radial);
  writeExr(path("disparity.exr"), r.disparity);
  FlowImage flo = r.warp;
  for (auto& v : flo.data)
    if (!std::isfinite(v.x) || !std::isfinite(v.y)) v = {kFloUnknown, kFloUnknown};
  writeFlo(path("flow.flo"), flo);
  const bool hasConfidence = !r.confidence.empty();
  if (hasConfidence) {
    writeExr(path("confidence.exr"), r.confidence);
    writePngRgb(path("confidence.png"), colorizeScalar(r.confidence, 0.f, 1.f));
  }
  std::vector<PlyPoint> points;
  for (size_t i = 0; i < r.depth.points.size(); ++i) {
    const Point3f& p = r.depth.points.data[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    if (hasConfidence && !(r.confidence.data[i] >= minConfidence)) continue;
    float g = std::min(1.f, std::max(0.f, left.data[i]));
    points.push_back({p.x, p.y, p.z, uint8_t(std::lround(255.f * g))});
  }
  writePly(path("points.ply"), points);
}

Progress::Progress(std::string label) : label_(std::move(label)), tty_(isatty(fileno(stderr))) {}

void Progress::operator()(double fraction) {
  int percent = int(std::floor(100.0 * std::min(1.0, std::max(0.0, fraction))));
  if (percent == lastPercent_) return;
  // On a terminal the line updates in place; in logs only every 25 % is printed.
  if (tty_) {
    std::fprintf(stderr, "\r%s %3d%%", label_.c_str(), percent);
  } else if (percent / 25 != lastPercent_ / 25 || lastPercent_ < 0) {
    std::fprintf(stderr, "%s %3d%%\n", label_.c_str(), percent);
  }
  std::fflush(stderr);
  lastPercent_ = percent;
}

void Progress::done() {
  if (tty_ && lastPercent_ >= 0) std::fprintf(stderr, "\r%s done\n", label_.c_str());
  lastPercent_ = -1;
}

std::string formatStages(const std::vector<StageTime>& stages) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  for (size_t i = 0; i < stages.size(); ++i) s << (i ? " | " : "") << stages[i].name << " " << stages[i].ms << " ms";
  return s.str();
}

}  // namespace cs::cli

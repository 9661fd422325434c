#include "common.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "curvestereo/image_io.hpp"

namespace cs::cli {

const std::set<std::string> kSolverOptions = {"preset", "warps",   "iterations", "levels",  "lambda", "du-max",
                                              "alpha0", "alpha1",  "max-fov",    "gamma",   "median", "backend",
                                              "mask",   "epipole", "beta",       "eta",    "device"};

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
  p.lambda = float(args.getDouble("lambda", p.lambda));
  p.duMax = float(args.getDouble("du-max", p.duMax));
  p.alpha0 = float(args.getDouble("alpha0", p.alpha0));
  p.alpha1 = float(args.getDouble("alpha1", p.alpha1));
  p.beta = float(args.getDouble("beta", p.beta));
  p.eta = float(args.getDouble("eta", p.eta));
  p.gamma = float(args.getDouble("gamma", p.gamma));
  p.maxFovDeg = args.getDouble("max-fov", p.maxFovDeg);
  p.epipoleDeg = args.getDouble("epipole", p.epipoleDeg);
  if (args.has("median")) {
    std::string m = args.get("median", "on");
    if (m != "on" && m != "off") throw Error("option --median expects on or off, got '" + m + "'");
    p.medianFilter = m == "on";
  }
  p.validate();
  return p;
}

ImageF loadImageFor(const std::string& path, const Camera& cam, const char* which) {
  ImageF img = readPngGray(path);
  if (img.width != cam.width || img.height != cam.height)
    throw Error(std::string(which) + " image '" + path + "' is " + std::to_string(img.width) + "x" +
                std::to_string(img.height) + " but the calibration is for " + std::to_string(cam.width) + "x" +
                std::to_string(cam.height));
  return img;
}

void writeDepthPng(const std::string& path, const ImageF& radialDepth) {
  // Inverse depth spreads near and far structure evenly; the range comes from the
  // 2nd/98th percentiles so a few outliers do not wash the picture out.
  ImageF inv(radialDepth.width, radialDepth.height, NAN);
  std::vector<float> finite;
  for (size_t i = 0; i < inv.size(); ++i) {
    float d = radialDepth.data[i];
    if (std::isnan(d) || d <= 0) continue;
    inv.data[i] = std::isinf(d) ? 0.f : 1.f / d;
    finite.push_back(inv.data[i]);
  }
  float lo = 0.f, hi = 1.f;
  if (!finite.empty()) {
    std::sort(finite.begin(), finite.end());
    lo = finite[size_t(0.02 * double(finite.size() - 1))];
    hi = finite[size_t(0.98 * double(finite.size() - 1))];
    if (hi <= lo) hi = lo + 1e-3f;
  }
  writePngRgb(path, colorizeScalar(inv, lo, hi));
}

void writeOutputs(const std::string& dir, const DepthResult& r, const ImageF& left) {
  std::filesystem::create_directories(dir);
  auto path = [&](const char* name) { return (std::filesystem::path(dir) / name).string(); };
  writeExr(path("depth.exr"), r.depth.radial);
  writeDepthPng(path("depth.png"), r.depth.radial);
  writeExr(path("disparity.exr"), r.disparity);
  FlowImage flo = r.warp;
  for (auto& v : flo.data)
    if (!std::isfinite(v.x) || !std::isfinite(v.y)) v = {kFloUnknown, kFloUnknown};
  writeFlo(path("flow.flo"), flo);
  std::vector<PlyPoint> points;
  for (size_t i = 0; i < r.depth.points.size(); ++i) {
    const Point3f& p = r.depth.points.data[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
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

#include "common.hpp"

#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "curvestereo/depth_views.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/param_table.hpp"

namespace cs::cli {

namespace {

// The options that are not parameters of the solver, then both spellings of each parameter.
std::set<std::string> solverOptions() {
  std::set<std::string> names = {"preset", "backend", "device", "mask"};
  for (const ParamInfo& info : paramTable()) names.insert({info.cliName(), info.cliLongName()});
  return names;
}

}  // namespace

const std::set<std::string> kSolverOptions = solverOptions();

std::string solverUsage() {
  std::string presets;
  for (const std::string& name : presetNames()) presets += (presets.empty() ? "" : "|") + name;
  std::string s =
      "solver options (run, demo, eval, bench):\n"
      "  --backend auto|cpu|...  --device INDEX|NAME  --mask PNG (run)\n";
  s += "  --preset " + presets + " (default: realtime)\n";
  s += "  --min-confidence C (run, demo: points.ply keeps points of at least this confidence)\n";
  const char* group = "";
  for (const ParamInfo& info : paramTable()) {
    if (std::string(info.group) != group) s += std::string(info.group) + ":\n";
    group = info.group;
    std::string value;
    switch (info.type) {
      case ParamInfo::Type::Int:
        value = "N";
        break;
      case ParamInfo::Type::Float:
      case ParamInfo::Type::Double:
        value = "X";
        break;
      case ParamInfo::Type::Bool:
        value = "on|off";
        break;
      case ParamInfo::Type::Enum:
        for (const auto& c : info.choices) value += (value.empty() ? "" : "|") + c;
        break;
    }
    std::string option = "  --" + info.cliName() + " " + value;
    if (option.size() < 36) option.resize(36, ' ');
    const std::string range = info.rangeText();
    s += option + " " + info.help + (range.empty() ? "" : " (" + range + ")") + "\n";
  }
  return s;
}

std::string backendFromArgs(const Args& args) {
  std::string backend = args.get("backend", "auto");
  if (args.has("device")) backend += ":" + args.get("device", "");
  return backend;
}

Params paramsFromArgs(const Args& args) {
  Params p = preset(args.get("preset", "realtime"));
  // In the table's order: --data-term sets its default lambda before an explicit --lambda.
  for (const ParamInfo& info : paramTable()) {
    const std::string shortName = info.cliName(), longName = info.cliLongName();
    if (args.has(shortName) && args.has(longName) && shortName != longName)
      throw Error("options --" + shortName + " and --" + longName + " set the same parameter");
    const std::string opt = args.has(longName) ? longName : shortName;
    if (!args.has(opt)) continue;
    switch (info.type) {
      case ParamInfo::Type::Int:
        info.setNumber(p, args.getInt(opt, 0));
        break;
      case ParamInfo::Type::Float:
      case ParamInfo::Type::Double:
        info.setNumber(p, args.getDouble(opt, 0.0));
        break;
      case ParamInfo::Type::Bool: {
        const std::string m = args.get(opt, "on");
        if (m != "on" && m != "off") throw Error("option --" + opt + " expects on or off, got '" + m + "'");
        info.setFlag(p, m == "on");
        break;
      }
      case ParamInfo::Type::Enum:
        info.setChoiceNamed(p, args.get(opt, ""));
        break;
    }
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
  ImageF left = loadImage(leftPath, "left"), right = loadImage(rightPath, "right");
  // A calibration without an image size (OpenCV's stereoCalibrate output) is for these images.
  CalibHints hints;
  hints.width = left.width;
  hints.height = left.height;
  StereoInputs in{loadCalibration(calib, nullptr, hints), std::move(left), std::move(right)};
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

CalibHints calibHintsFromArgs(const Args& args) {
  CalibHints hints;
  if (!args.has("image-size")) return hints;
  const std::string text = args.get("image-size", "");
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') || w < 1 || h < 1 ||
      w > 1000000 || h > 1000000)
    throw Error("--image-size must be WIDTHxHEIGHT in pixels (e.g. 848x800), got '" + text + "'");
  hints.width = w;
  hints.height = h;
  return hints;
}

void writeDepthPng(const std::string& path, const ImageF& radialDepth) { writePngRgb(path, depthPicture(radialDepth)); }

float minConfidenceFromArgs(const Args& args) {
  if (!args.has("min-confidence")) return 0.f;
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

void writeOrganisedCloud(const std::string& dir, const DepthResult& r, float minConfidence) {
  Image<Point3f> points = r.depth.points;
  if (!r.confidence.empty())
    for (size_t i = 0; i < points.size(); ++i)
      if (!(r.confidence.data[i] >= minConfidence)) points.data[i] = {NAN, NAN, NAN};
  writePcd((std::filesystem::path(dir) / "points.pcd").string(), points);
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

ImageU8 loadMask(const std::string& path) {
  const ImageF m = readPngGray(path);
  ImageU8 out(m.width, m.height);
  for (size_t i = 0; i < m.size(); ++i) out.data[i] = m.data[i] > 0.5f;
  return out;
}

// --calib, or the sequence folder's own camchain.yaml: beside mav0/ (the ASL layout keeps
// it there), inside it, or, when the source is mav0/ itself, beside that.
std::string sequenceCalibration(const Args& args, const std::string& source) {
  if (args.has("calib")) return args.get("calib", "");
  namespace fs = std::filesystem;
  fs::path dir = fs::path(source).lexically_normal();
  if (dir.filename().empty()) dir = dir.parent_path();  // "seq/mav0/"
  std::vector<fs::path> candidates = {dir / "camchain.yaml", dir / "mav0" / "camchain.yaml"};
  if (dir.filename() == "mav0") candidates.push_back(dir.parent_path() / "camchain.yaml");
  std::error_code ec;
  for (const fs::path& own : candidates)
    if (fs::is_regular_file(own, ec)) {
      std::fprintf(stderr, "curvestereo: note: calibration %s\n", own.string().c_str());
      return own.string();
    }
  throw Error("sequence '" + source + "' has no camchain.yaml (beside mav0/): give one with --calib CALIB");
}

int readThreads(const Args& args) {
  const std::string text = args.get("read-threads", "0");
  int n = 0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), n);
  if (r.ec != std::errc() || r.ptr != text.data() + text.size() || n < 0 || n > 64)
    throw UsageError("--read-threads expects a whole number of 0 to 64 (0: by the core count), got '" + text + "'");
  return n;
}

// A whole number that is all of text.
bool wholeNumber(const std::string& text, int& out) {
  const auto r = std::from_chars(text.data(), text.data() + text.size(), out);
  return r.ec == std::errc() && r.ptr == text.data() + text.size();
}

// --frames FIRST:END: frames FIRST .. END-1 alone (either may be left out), e.g. one part of
// a long recording as a batch task; the warm start begins at FIRST.
std::pair<size_t, size_t> frameRange(const Args& args, size_t n) {
  if (!args.has("frames")) return {0, n};
  const std::string text = args.get("frames", "");
  const size_t colon = text.find(':');
  int first = 0, end = int(std::min<size_t>(n, size_t(INT32_MAX)));
  const bool endGiven = colon != std::string::npos && colon + 1 < text.size();
  if (colon == std::string::npos || (colon > 0 && !wholeNumber(text.substr(0, colon), first)) ||
      (endGiven && !wholeNumber(text.substr(colon + 1), end)) || first < 0 || (endGiven && end <= first))
    throw UsageError("--frames expects FIRST:END, frame indexes with FIRST < END (either may be left out), got '" +
                     text + "'");
  if (size_t(first) >= n)
    throw Error("--frames " + text + ": the sequence has " + std::to_string(n) + " frames (0 to " +
                std::to_string(n - 1) + ")");
  return {size_t(first), std::min(size_t(end), n)};
}

Summary summarize(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  const double median = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  return {median, v.front(), v.back()};
}

}  // namespace cs::cli

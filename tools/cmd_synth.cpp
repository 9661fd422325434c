// curvestereo synth: renders a synthetic stereo pair with exact ground-truth depth in
// the layout of ../shared/data/synthetic (left.png right.png depth_left.exr
// depth_right.exr camchain.yaml), optionally through a camera model (--camera t265:
// dark, vignetted, noisy, as a real low-cost fisheye camera), which also writes
// photometry.json. Without camera options the output is the clean renderer's.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "camera_options.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/image_io.hpp"
#include "synth/scene.hpp"

namespace cs::cli {
namespace {

// Options that describe a synthetic rig; they make no sense next to --calib.
const char* const kRigOptions[] = {"motion", "baseline", "rotation"};

// The rig's cameras rescaled so that camera 0 is `size` pixels wide.
Rig scaledRig(Rig rig, int size) {
  const double s = double(size) / rig.cam0.width;
  rig.cam0 = rig.cam0.scaled(s);
  rig.cam1 = rig.cam1.scaled(s);
  return rig;
}

synth::SynthConfig configFromArgs(const Args& args) {
  synth::SynthConfig cfg;
  cfg.scene = args.get("scene", "urban");
  const int seed = args.getInt("seed", 1);
  if (seed < 0) throw Error("option --seed expects a non-negative integer");
  cfg.seed = uint32_t(seed);
  cfg.nearest = args.getDouble("nearest", cfg.nearest);
  cfg.samplesPerAxis = args.getInt("samples", cfg.samplesPerAxis);
  const int size = args.getInt("size", 800);
  if (size < 16 || size > 16384) throw Error("option --size expects 16..16384 pixels");
  if (args.has("calib")) {
    for (const char* option : kRigOptions)
      if (args.has(option)) throw Error(std::string("option --") + option + " cannot be combined with --calib");
    Rig rig = loadCalibration(args.get("calib", ""));
    cfg.rig = args.has("size") ? scaledRig(rig, size) : rig;
    cfg.maxFovDeg = args.getDouble("fov", 0.0);  // a calibrated lens: its own valid region
  } else {
    cfg.camera = synth::defaultFisheye(size);
    cfg.motion = args.get("motion", cfg.motion);
    cfg.baseline = args.getDouble("baseline", cfg.baseline);
    cfg.rotationDeg = args.getDouble("rotation", cfg.rotationDeg);
    cfg.maxFovDeg = args.getDouble("fov", 180.0);
  }
  return cfg;
}

struct DepthRange {
  double nearest = std::numeric_limits<double>::infinity(), farthest = 0.0, skyFraction = 0.0;
};

DepthRange depthRange(const ImageF& depth) {
  DepthRange r;
  long valid = 0, sky = 0;
  for (float d : depth.data) {
    if (!(d > 0.f)) continue;
    ++valid;
    if (std::isinf(d)) {
      ++sky;
      continue;
    }
    r.nearest = std::min(r.nearest, double(d));
    r.farthest = std::max(r.farthest, double(d));
  }
  r.skyFraction = valid ? double(sky) / double(valid) : 0.0;
  return r;
}

// The images at the camera model's bit depth (8 without a model, as always).
void writePair(const synth::SynthPair& pair, const synth::CameraPhotometry& camera, const std::string& outDir) {
  std::filesystem::create_directories(outDir);
  auto path = [&](const char* name) { return (std::filesystem::path(outDir) / name).string(); };
  writePairImage(path("left.png"), pair.left, camera);
  writePairImage(path("right.png"), pair.right, camera);
  writeExr(path("depth_left.exr"), pair.depthLeft);
  writeExr(path("depth_right.exr"), pair.depthRight);
  saveKalibr(pair.rig, path("camchain.yaml"));
}

void printSummary(const synth::SynthConfig& cfg, const synth::SynthPair& pair, double seconds,
                  const std::string& outDir, const std::string& camera) {
  const Eigen::Vector3d centre1 = -pair.rig.R.transpose() * pair.rig.t;
  const double angle = std::acos(std::clamp(0.5 * (pair.rig.R.trace() - 1.0), -1.0, 1.0)) * 180.0 / M_PI;
  const DepthRange left = depthRange(pair.depthLeft);
  std::printf("%s scene, seed %u, %s %dx%d, %d x %d samples per pixel\n", cfg.scene.c_str(), cfg.seed,
              pair.rig.cam0.modelName().c_str(), pair.rig.cam0.width, pair.rig.cam0.height, cfg.samplesPerAxis,
              cfg.samplesPerAxis);
  std::printf("camera 1 centre in camera 0: (%.3f, %.3f, %.3f) m (baseline %.3f m), rotation %.2f deg\n", centre1.x(),
              centre1.y(), centre1.z(), centre1.norm(), angle);
  std::printf("depth (left): %.2f .. %.1f m, sky %.1f %% of valid pixels\n", left.nearest, left.farthest,
              100.0 * left.skyFraction);
  if (!camera.empty()) std::printf("camera model %s\n", camera.c_str());
  std::printf("rendered in %.1f s; wrote %s/{left,right}.png depth_{left,right}.exr camchain.yaml%s\n", seconds,
              outDir.c_str(), camera.empty() ? "" : " photometry.json");
}

}  // namespace

int cmdSynth(const Args& args) {
  std::set<std::string> known = kCameraOptions;
  known.insert({"o", "output", "scene", "seed", "size", "calib", "motion", "baseline", "rotation", "nearest", "samples",
                "fov", "quiet"});
  args.allowOnly(known);
  const std::string outDir = args.get("o", args.get("output", ""));
  if (outDir.empty()) throw Error("synth: missing output folder (-o OUTDIR)");
  const synth::SynthConfig cfg = configFromArgs(args);
  const synth::CameraPhotometry camera = cameraModelFromArgs(args, cfg.seed);  // checked before the long render

  const bool quiet = args.has("quiet");
  Progress leftProgress("rendering left"), rightProgress("rendering right");
  auto report = [&](double f) {
    if (quiet) return;
    if (f < 0.5) {
      leftProgress(2.0 * f);
    } else {
      if (f == 0.5) leftProgress.done();
      rightProgress(2.0 * f - 1.0);
    }
  };
  const auto start = std::chrono::steady_clock::now();
  synth::SynthPair pair = synth::renderPair(cfg, report);
  if (!quiet) rightProgress.done();
  const double exposureScale = synth::applyPhotometry(camera, pair);  // depth untouched
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  writePair(pair, camera, outDir);
  if (camera.enabled()) writePhotometryJson(camera, exposureScale, outDir);
  printSummary(cfg, pair, seconds, outDir, camera.enabled() ? synth::describePhotometry(camera, exposureScale) : "");
  return 0;
}

}  // namespace cs::cli

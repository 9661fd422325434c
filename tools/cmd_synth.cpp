// curvestereo synth: renders a synthetic stereo pair with exact ground-truth depth in
// the layout of ../shared/data/synthetic (left.png right.png depth_left.exr
// depth_right.exr camchain.yaml), optionally through a camera model (--camera t265:
// dark, vignetted, noisy, as a real low-cost fisheye camera), which also writes
// photometry.json. Without camera options the output is the clean renderer's.
// With --sequence it renders a walking rig's stereo sequence in the EuRoC / ASL layout
// instead (tools/synth/sequence.hpp); with --rig LAYOUT an N-camera rig with each camera's
// depth and the 360-degree range panorama, in the ../shared/data/rigs layout (tools/synth/rig.hpp).
#include <unistd.h>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>

#include "camera_options.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/image_io.hpp"
#include "synth/rig.hpp"
#include "synth/scene.hpp"
#include "synth/sequence.hpp"

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

// Sequences default to a smaller, faster render than pairs.
struct RenderDefaults {
  int size = 800;
  int samples = 3;
};

// --seed and --size, as a pair, a sequence and a rig read them.
uint32_t seedFromArgs(const Args& args) {
  const int seed = args.getInt("seed", 1);
  if (seed < 0) throw Error("option --seed expects a non-negative integer");
  return uint32_t(seed);
}

int sizeFromArgs(const Args& args, int fallback) {
  const int size = args.getInt("size", fallback);
  if (size < 16 || size > 16384) throw Error("option --size expects 16..16384 pixels");
  return size;
}

synth::SynthConfig configFromArgs(const Args& args, RenderDefaults defaults = {}) {
  synth::SynthConfig cfg;
  cfg.scene = args.get("scene", "urban");
  cfg.seed = seedFromArgs(args);
  cfg.nearest = args.getDouble("nearest", cfg.nearest);
  cfg.samplesPerAxis = args.getInt("samples", defaults.samples);
  const int size = sizeFromArgs(args, defaults.size);
  if (args.has("calib")) {
    for (const char* option : kRigOptions)
      if (args.has(option)) throw UsageError(std::string("option --") + option + " cannot be combined with --calib");
    Rig rig = loadCalibration(args.get("calib", ""), nullptr, calibHintsFromArgs(args));
    cfg.rig = args.has("size") ? scaledRig(rig, size) : rig;
    // Ground truth where the solver solves by default (Params::maxFovDeg), so that eval does
    // not count a ring the solver was never asked for as missing; --fov widens both sides
    // alike (pass the same value to run as max_fov_deg).
    cfg.maxFovDeg = args.getDouble("fov", Params{}.maxFovDeg);
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

// ---------------------------------------------------------------- --sequence

const char* const kSequenceOptions[] = {"frames", "fps", "speed", "turn", "mover"};

synth::SequenceConfig sequenceFromArgs(const Args& args) {
  synth::SequenceConfig seq;
  seq.render = configFromArgs(args, RenderDefaults{400, 2});
  seq.frames = args.getInt("frames", seq.frames);
  seq.fps = args.getDouble("fps", seq.fps);
  seq.speed = args.getDouble("speed", seq.speed);
  seq.turnDegPerS = args.getDouble("turn", seq.turnDegPerS);
  const std::string mover = args.get("mover", "on");
  if (mover != "on" && mover != "off") throw Error("option --mover expects on or off, got '" + mover + "'");
  seq.mover = mover == "on";
  seq.validate();
  return seq;
}

void printSequenceSummary(const synth::SequenceRenderer& renderer, const synth::SequenceReport& report,
                          const std::string& outDir, const std::string& camera) {
  const synth::SequenceConfig& seq = renderer.config();
  const Camera& cam0 = renderer.rig().cam0;
  std::printf("%s scene, seed %u, %d frames at %g fps (%.2f s), %s %dx%d, %d x %d samples per pixel\n",
              seq.render.scene.c_str(), seq.render.seed, seq.frames, seq.fps, renderer.seconds(seq.frames - 1),
              cam0.modelName().c_str(), cam0.width, cam0.height, seq.render.samplesPerAxis, seq.render.samplesPerAxis);
  std::printf("walk: %.2f m at %g m/s along camera 0's z, turning %.1f deg (%g deg/s, > 0 left), bob %g cm\n",
              report.pathLength, seq.speed, report.headingChangeDeg, seq.turnDegPerS, 100.0 * seq.bobM);
  if (const auto& m = renderer.mover()) {
    const Eigen::Vector3d size = 2.0 * m->halfSize;
    std::printf("mover: box %.2f x %.2f x %.2f m at %.2f m/s, seen by camera 0 in %d/%d frames", size.x(), size.y(),
                size.z(), m->velocity.norm(), report.moverFrames, report.frames);
    if (report.moverFarthest > 0.0)
      std::printf(" at %.2f .. %.2f m (up to %.2f %% of the image)", report.moverNearest, report.moverFarthest,
                  100.0 * report.moverShareMax);
    std::printf("\n");
  }
  if (!camera.empty()) std::printf("camera model %s\n", camera.c_str());
  std::printf(
      "rendered %d frames in %.1f s (%.2f s per frame); wrote %s/mav0/{%s} poses_cam0.csv camchain.yaml "
      "meta.json%s\n",
      report.frames, report.seconds, report.seconds / report.frames, outDir.c_str(),
      renderer.mover() ? "cam0,cam1,depth0,depth1,mover0,mover1" : "cam0,cam1,depth0,depth1",
      camera.empty() ? "" : " photometry.json");
}

int synthSequence(const Args& args) {
  const std::string outDir = args.get("o", args.get("output", ""));
  if (outDir.empty()) throw UsageError("synth: missing output folder (-o OUTDIR)");
  const synth::SequenceConfig seq = sequenceFromArgs(args);
  const synth::CameraPhotometry camera = cameraModelFromArgs(args, seq.render.seed);  // checked before the render
  const synth::SequenceRenderer renderer(seq);  // plans the walk and the mover; throws before rendering

  const bool quiet = args.has("quiet"), bar = !quiet && isatty(fileno(stderr));
  std::optional<Progress> progress;
  synth::SequenceCallbacks callbacks;
  callbacks.rendering = [&](int frame, double fraction) {
    if (!bar) return;
    if (!progress) progress.emplace("frame " + std::to_string(frame + 1) + "/" + std::to_string(seq.frames));
    (*progress)(fraction);
  };
  callbacks.frameDone = [&](const synth::SequenceFrameReport& r) {
    if (progress) progress->done();
    progress.reset();
    if (quiet) return;
    std::printf("frame %*d/%d  t %lld  %.2f s  nearest %.2f m", int(std::to_string(seq.frames).size()), r.index + 1,
                seq.frames, (long long)r.timestampNs, r.seconds, r.nearest);
    if (renderer.mover())
      std::printf("  mover %.2f / %.2f %% of cameras 0 / 1", 100.0 * r.moverShare[0], 100.0 * r.moverShare[1]);
    std::printf("\n");
    std::fflush(stdout);
  };
  const synth::SequenceReport report = synth::writeSequence(renderer, camera, outDir, callbacks);
  printSequenceSummary(renderer, report, outDir,
                       camera.enabled() ? synth::describePhotometry(camera, report.exposureScale) : "");
  return 0;
}

// ---------------------------------------------------------------- --rig

// Options of a pair or a sequence that a rig's layout fixes or that it does not model.
const char* const kNotForRigs[] = {"calib", "motion", "baseline", "rotation", "fov", "sequence", "image-size"};

synth::RigConfig rigFromArgs(const Args& args) {
  for (const char* option : kNotForRigs)
    if (args.has(option)) throw UsageError(std::string("option --") + option + " cannot be combined with --rig");
  for (const char* option : kSequenceOptions)
    if (args.has(option)) throw UsageError(std::string("option --") + option + " cannot be combined with --rig");
  for (const std::string& option : kCameraOptions)
    if (args.has(option)) throw UsageError("option --" + option + " cannot be combined with --rig (clean images only)");
  synth::RigConfig cfg;
  cfg.layout = args.get("rig", "");
  try {
    synth::rigLayout(cfg.layout, 16);  // the name checked before anything else
  } catch (const Error& e) {
    throw UsageError(e.what());
  }
  cfg.scene = args.get("scene", cfg.scene);
  cfg.seed = seedFromArgs(args);
  cfg.size = sizeFromArgs(args, cfg.size);
  cfg.samplesPerAxis = args.getInt("samples", cfg.samplesPerAxis);
  cfg.nearest = args.getDouble("nearest", cfg.nearest);
  cfg.panoramaWidth = args.getInt("panorama-width", cfg.panoramaWidth);
  if (cfg.panoramaWidth < 4 || cfg.panoramaWidth > 32768 || cfg.panoramaWidth % 2 != 0)
    throw UsageError("--panorama-width expects an even width of 4 to 32768 px (the image is W x W/2)");  // as run
  return cfg;
}

void printRigSummary(const synth::RigConfig& cfg, const synth::SynthRig& r, double seconds, const std::string& outDir) {
  const CameraRig& rig = r.layout.rig;
  std::printf("%s scene, seed %u, rig %s: %s\n", cfg.scene.c_str(), cfg.seed, r.layout.name.c_str(),
              r.layout.description.c_str());
  std::printf("%d cameras %s %dx%d (%g deg), %d x %d samples per pixel\n", rig.size(),
              rig.cameras.front().modelName().c_str(), cfg.size, cfg.size, r.layout.maxFovDeg, cfg.samplesPerAxis,
              cfg.samplesPerAxis);
  for (int k = 0; k < rig.size(); ++k) {
    const DepthRange d = depthRange(r.depths[size_t(k)]);
    const Eigen::Vector3d& p = rig.poses[size_t(k)].p;
    std::printf("cam%d at (%.3f, %.3f, %.3f) m: depth %.2f .. %.1f m, sky %.1f %%\n", k, p.x(), p.y(), p.z(), d.nearest,
                d.farthest, 100.0 * d.skyFraction);
  }
  const DepthRange pano = depthRange(r.panoramaRange);
  std::printf("panorama %dx%d: range %.2f .. %.1f m, sky %.1f %%\n", r.panoramaRange.width, r.panoramaRange.height,
              pano.nearest, pano.farthest, 100.0 * pano.skyFraction);
  std::printf(
      "rendered in %.1f s; wrote %s/{cam<k>.png,depth<k>.exr} camchain.yaml panorama_range.exr panorama.png "
      "rig.json\n",
      seconds, outDir.c_str());
}

int synthRig(const Args& args) {
  const synth::RigConfig cfg = rigFromArgs(args);
  const std::string outDir = args.get("o", args.get("output", ""));
  if (outDir.empty()) throw UsageError("synth: missing output folder (-o OUTDIR)");
  const bool quiet = args.has("quiet");
  Progress progress("rendering rig " + cfg.layout);
  const auto start = std::chrono::steady_clock::now();
  const synth::SynthRig rig = synth::renderRig(cfg, [&](double f) {
    if (!quiet) progress(f);
  });
  if (!quiet) progress.done();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  synth::writeRigFolder(rig, cfg, outDir);
  printRigSummary(cfg, rig, seconds, outDir);
  return 0;
}

}  // namespace

int cmdSynth(const Args& given) {
  std::set<std::string> known = kCameraOptions;
  known.insert({"o", "output", "scene", "seed", "size", "calib", "motion", "baseline", "rotation", "nearest", "samples",
                "fov", "quiet", "sequence", "image-size", "rig", "panorama-width"});
  for (const char* option : kSequenceOptions) known.insert(option);
  given.allowOnly(known);
  if (!given.get("sequence", "").empty())
    throw UsageError("option --sequence takes no value, got '" + given.get("sequence", "") + "'");
  if (given.has("rig")) return synthRig(given);
  if (given.has("panorama-width")) throw UsageError("option --panorama-width needs --rig");
  if (given.has("sequence")) return synthSequence(given);
  const Args& args = given;
  for (const char* option : kSequenceOptions)
    if (args.has(option)) throw UsageError(std::string("option --") + option + " needs --sequence");
  const std::string outDir = args.get("o", args.get("output", ""));
  if (outDir.empty()) throw UsageError("synth: missing output folder (-o OUTDIR)");
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

// curvestereo run --calib RIG IMG0 IMG1 ... -o OUTDIR [--pairs I-J,...] [--partners N]
//                 [--panorama-width W] [solver options]
// curvestereo run --sequence DIR [--calib RIG] -o OUTDIR [rig options]: a rig's recording
// (cam0 ... cam<N-1>), frame after frame into OUTDIR/<t_ns>/.
// A rig of N cameras: its pairs solved, each camera's outputs in OUTDIR/cam<k>/ under a pair
// run's names, the panorama and the merged cloud in OUTDIR.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/camera_rig.hpp"
#include "curvestereo/depth_views.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/rig_fusion.hpp"
#include "curvestereo/rig_sequence.hpp"
#include "curvestereo/rig_stereo.hpp"
#include "rig_cli.hpp"

namespace cs::cli {

namespace {

int panoramaWidth(const Args& args) {
  const int width = args.getInt("panorama-width", 2048);
  if (width < 4 || width % 2 || width > 32768)
    throw UsageError("--panorama-width expects an even width of 4 to 32768 px (the image is W x W/2)");
  return width;
}

void writePanorama(const std::string& dir, const Panorama& p) {
  auto path = [&](const char* name) { return (std::filesystem::path(dir) / name).string(); };
  writeExr(path("panorama_range.exr"), p.range);
  writeExr(path("panorama_confidence.exr"), p.confidence);
  ImageF grey = p.grey;
  for (float& g : grey.data) g = std::isfinite(g) ? g : 0.f;
  writePngGray(path("panorama.png"), grey);
  writeDepthPng(path("panorama_depth.png"), p.range);
}

void writeMergedCloud(const std::string& dir, const std::vector<RigPoint>& points) {
  std::vector<PlyPoint> ply;
  ply.reserve(points.size());
  Image<Point3f> pcd(int(points.size()), 1);
  for (size_t k = 0; k < points.size(); ++k) {
    const RigPoint& p = points[k];
    ply.push_back({p.x, p.y, p.z, uint8_t(std::lround(255.f * std::clamp(p.grey, 0.f, 1.f)))});
    pcd.data[k] = {p.x, p.y, p.z};
  }
  writePly((std::filesystem::path(dir) / "points.ply").string(), ply);
  if (!points.empty()) writePcd((std::filesystem::path(dir) / "points.pcd").string(), pcd);
}

// A frame's outputs: each camera's in DIR/cam<k>/ under a pair run's names, the panorama and
// the merged cloud in DIR.
void writeRigFrame(const std::string& dir, const CameraRig& rig, const RigResult& r, const std::vector<ImageF>& images,
                   const Panorama& panorama, const PanoramaFrame& frame, float minConfidence) {
  for (int k = 0; k < rig.size(); ++k) {
    const std::string camDir = (std::filesystem::path(dir) / ("cam" + std::to_string(k))).string();
    writeOutputs(camDir, r.cameras[size_t(k)], images[size_t(k)], minConfidence);
    writeOrganisedCloud(camDir, r.cameras[size_t(k)], minConfidence);
  }
  writePanorama(dir, panorama);
  writeMergedCloud(dir, mergedPoints(rig, r.cameras, images, frame, minConfidence));
}

}  // namespace

std::vector<PairInfo> rigPairsFromArgs(const Args& args, const CameraRig& rig) {
  if (args.has("pairs")) {
    if (args.has("partners")) throw UsageError("give --pairs or --partners, not both");
    return parsePairs(rig, args.get("pairs", ""));
  }
  const int partners = args.getInt("partners", 2);
  if (partners < 1 || partners > 8) throw UsageError("--partners expects 1 to 8");
  return choosePairs(rig, partners);
}

// A lens wider than 180 degrees shows its whole image circle: unless the user sets the field
// of view, the solve uses the widest camera's.
Params rigParamsFromArgs(const Args& args, const CameraRig& rig) {
  const Params params = paramsFromArgs(args);
  if (args.has("max-fov") || args.has("max-fov-deg")) return params;
  return rigParams(rig, params);
}

std::unique_ptr<RigStereo> rigStereoFromArgs(const Args& args, const CameraRig& rig, const std::vector<PairInfo>& pairs,
                                             const Params& params) {
  const double crossCheck = args.getDouble("cross-check", 0.0);
  if (!(crossCheck >= 0.0 && crossCheck <= 1.0))
    throw UsageError("--cross-check expects a tolerance in [0, 1] (e.g. 0.1)");
  auto stereo = std::make_unique<RigStereo>(rig, pairs, params, backendFromArgs(args), !args.has("whole-images"));
  stereo->setCrossCheck(crossCheck);
  stereo->setOneWay(args.has("one-way"));
  return stereo;
}

float panoramaMinConfidence(const Args& args) {
  const double c = args.getDouble("panorama-min-confidence", 0.0);
  if (!(c >= 0.0 && c <= 1.0)) throw UsageError("--panorama-min-confidence expects a number in [0, 1]");
  return float(c);
}

std::string describePairs(const std::vector<PairInfo>& pairs) {
  std::string out;
  for (const PairInfo& p : pairs) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s%d-%d (overlap %.0f %% / %.0f %%, baseline %.3f m)", out.empty() ? "" : ", ", p.i,
                  p.j, 100.0 * p.overlapIJ, 100.0 * p.overlapJI, p.baseline);
    out += buf;
  }
  return out;
}

double validShare(const DepthResult& r) {
  long long valid = 0;
  for (auto v : r.valid.data) valid += v;
  return r.valid.size() ? double(valid) / double(r.valid.size()) : 0.0;
}

int runRig(const Args& args, const std::string& outDir) {
  const CameraRig rig = loadCameraRig(args.require("calib"));
  const std::vector<std::string>& paths = args.positional();
  if (int(paths.size()) != rig.size())
    throw UsageError("the rig has " + std::to_string(rig.size()) + " cameras: run needs " + std::to_string(rig.size()) +
                     " images, one per camera in order, got " + std::to_string(paths.size()));
  const std::vector<PairInfo> pairs = rigPairsFromArgs(args, rig);
  const int width = panoramaWidth(args);
  const float minConfidence = minConfidenceFromArgs(args);
  const float panoramaConfidence = panoramaMinConfidence(args);
  const Params params = rigParamsFromArgs(args, rig);
  std::vector<ImageF> images;
  for (int k = 0; k < rig.size(); ++k)
    images.push_back(loadImageFor(paths[size_t(k)], rig.cameras[size_t(k)], ("cam" + std::to_string(k)).c_str()));

  const std::unique_ptr<RigStereo> solver = rigStereoFromArgs(args, rig, pairs, params);
  RigStereo& stereo = *solver;
  std::printf("backend: %s; settings: %s\n", stereo.backendName().c_str(), describe(params).c_str());
  std::printf("pairs: %s\n", describePairs(pairs).c_str());
  const PanoramaFrame frame = panoramaFrame(rig);
  stereo.setPanorama(width, frame, panoramaConfidence);
  const RigResult r = stereo.compute(images);
  for (const RigResult::Solve& s : r.solves)
    std::printf("  cam%d from cam%d: %.1f ms, %dx%d px at (%d, %d)%s\n", s.reference, s.other, s.ms, s.window.width,
                s.window.height, s.window.x0, s.window.y0,
                args.has("cross-check")
                    ? (", cross-check took " + std::to_string(s.crossCheckInvalidated) + " px").c_str()
                    : "");

  writeRigFrame(outDir, rig, r, images, r.panorama, frame, minConfidence);
  for (int k = 0; k < rig.size(); ++k)
    std::printf("cam%d: %.1f %% of the image has a depth\n", k, 100.0 * validShare(r.cameras[size_t(k)]));
  std::printf(
      "total %.1f ms: the pairs, the panorama %dx%d (%s; %.1f ms after the solves) and the per-camera "
      "fusion; outputs in %s\n",
      r.totalMs, width, width / 2, stereo.backendName().c_str(), r.panoramaMs, outDir.c_str());
  return 0;
}

bool isRigSequence(const Args& args) { return args.has("rig") || RigSequence::camerasIn(args.get("sequence", "")) > 2; }

int runRigSequence(const Args& args, const std::string& outDir) {
  const std::string source = args.get("sequence", "");
  const CameraRig rig = loadCameraRig(sequenceCalibration(args, source));
  SequenceOptions options;
  options.poses = args.get("poses", "");
  options.pairToleranceMs = args.getDouble("pair-tolerance-ms", options.pairToleranceMs);
  const RigSequence sequence = RigSequence::open(source, rig, options);
  const auto [first, end] = frameRange(args, sequence.frames().size());  // checked before any output
  for (const std::string& w : sequence.warnings()) std::fprintf(stderr, "curvestereo: warning: %s\n", w.c_str());
  Params params = rigParamsFromArgs(args, rig);
  const bool cold = args.has("cold");
  if (cold) params.warmStart = false, params.temporalStrength = 0.f;  // every frame alone: the baseline
  const std::vector<PairInfo> pairs = rigPairsFromArgs(args, rig);
  const float minConfidence = minConfidenceFromArgs(args);
  const std::unique_ptr<RigStereo> solver = rigStereoFromArgs(args, rig, pairs, params);
  RigStereo& stereo = *solver;
  const PanoramaFrame frame = panoramaFrame(rig);
  stereo.setPanorama(panoramaWidth(args), frame, panoramaMinConfidence(args));
  std::printf("sequence: %s\n", sequence.summary().c_str());
  std::printf("backend: %s; settings: %s; %s\n", stereo.backendName().c_str(), describe(params).c_str(),
              cold ? "cold: every frame solved alone" : "warm start and temporal filter");
  std::printf("pairs: %s\n", describePairs(pairs).c_str());
  const bool tty = isatty(fileno(stderr));
  const auto start = std::chrono::steady_clock::now();
  int frames = 0, warmSolves = 0, coldSolves = 0, redone = 0;
  double solveMs = 0;
  std::vector<ImageF> images;
  RigResult r;
  for (size_t i = first; i < end; ++i) {
    const RigSequenceFrame& f = sequence.frames()[i];
    const std::string name = std::to_string(f.timestampNs);
    const std::string written = " (" + std::to_string(frames) + " frames before it are written)";
    try {
      sequence.load(i, images);  // its errors name the frame
    } catch (const Error& e) {
      if (tty) std::fputc('\n', stderr);
      throw Error(e.what() + written);
    }
    try {
      stereo.next(images, r, f.hasPose ? &f.bodyPose : nullptr);
      writeRigFrame((std::filesystem::path(outDir) / name).string(), rig, r, images, r.panorama, frame, minConfidence);
    } catch (const Error& e) {
      if (tty) std::fputc('\n', stderr);
      throw Error("frame " + std::to_string(i) + " (t " + name + " ns): " + e.what() + written);
    }
    ++frames;
    solveMs += r.totalMs;
    for (const RigResult::Solve& s : r.solves) (s.warm ? warmSolves : coldSolves) += 1, redone += s.redone;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (tty || frames == int(end - first) || frames % 30 == 0)
      std::fprintf(stderr, "%sframe %d/%zu  %.1f ms solved  %.1f frames/s%s", tty ? "\r" : "", frames, end - first,
                   r.totalMs, frames / std::max(1e-9, seconds), tty ? "   " : "\n");
  }
  if (tty) std::fputc('\n', stderr);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "%d frames in %.1f s: %.1f ms a frame solved and fused per camera; %d solves warm, %d cold, %d warm ones "
      "redone cold; outputs in %s/<t_ns>/\n",
      frames, seconds, frames ? solveMs / frames : 0.0, warmSolves, coldSolves, redone, outDir.c_str());
  return 0;
}

int benchRig(const Args& args) {
  const CameraRig rig = loadCameraRig(args.require("calib"));
  const std::vector<std::string>& paths = args.positional();
  if (int(paths.size()) != rig.size())
    throw UsageError("the rig has " + std::to_string(rig.size()) + " cameras: bench needs " +
                     std::to_string(rig.size()) + " images, one per camera in order, got " +
                     std::to_string(paths.size()));
  const std::vector<PairInfo> pairs = rigPairsFromArgs(args, rig);
  const Params params = rigParamsFromArgs(args, rig);
  std::vector<ImageF> images;
  for (int k = 0; k < rig.size(); ++k)
    images.push_back(loadImageFor(paths[size_t(k)], rig.cameras[size_t(k)], ("cam" + std::to_string(k)).c_str()));
  const std::unique_ptr<RigStereo> solver = rigStereoFromArgs(args, rig, pairs, params);
  RigStereo& stereo = *solver;
  const bool serial = args.has("serial");
  stereo.setConcurrentSolves(!serial);
  stereo.setFlowOutputs(false);  // a panorama needs only the solves' depth and confidence
  stereo.setCameraOutputs(false);
  const int width = panoramaWidth(args);
  stereo.setPanorama(width, panoramaFrame(rig), panoramaMinConfidence(args));
  const int runs = args.getInt("runs", stereo.backendName() == "cpu" ? 1 : 20);
  std::printf("backend:  %s; settings: %s\n", stereo.backendName().c_str(), describe(params).c_str());
  std::printf("input:    %d cameras, %s\n", rig.size(), describePairs(pairs).c_str());
  std::printf("runs:     %d frames after 1 warm-up frame; %zu solves a frame, %s\n", runs, stereo.views().size(),
              serial ? "one after the other (--serial)" : "concurrently");
  std::vector<double> solves, slowest, panoramas, totals;
  Progress progress("benchmark");
  RigResult r;  // reused, as a real-time loop would
  for (int i = 0; i <= runs; ++i) {
    const auto start = std::chrono::steady_clock::now();
    stereo.compute(images, r);
    const auto end = std::chrono::steady_clock::now();
    if (i == 0) continue;  // the warm-up: allocations, first-use compilation
    solves.push_back(r.totalMs - r.fusionMs);
    double longest = 0;
    for (const RigResult::Solve& solve : r.solves) longest = std::max(longest, solve.ms);
    slowest.push_back(longest);
    panoramas.push_back(r.panoramaMs);
    totals.push_back(std::chrono::duration<double, std::milli>(end - start).count());
    progress(double(i) / runs);
  }
  progress.done();
  std::printf("frame:    median %.2f ms (%.1f fps), images in memory to the panorama in memory\n",
              summarize(totals).median, 1000.0 / summarize(totals).median);
  std::printf("  solves:   median %.2f ms (the slowest %.2f ms)%s\n", summarize(solves).median,
              summarize(slowest).median,
              args.getDouble("cross-check", 0.0) > 0 ? "" : ", each placing its view in the panorama as it ends");
  std::printf("  panorama %dx%d (%s) after the solves: median %.2f ms\n", width, width / 2,
              stereo.backendName().c_str(), summarize(panoramas).median);
  return 0;
}

}  // namespace cs::cli

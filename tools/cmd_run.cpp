// curvestereo run --calib CALIB LEFT RIGHT -o OUTDIR [--backend B] [--preset P] [--mask PNG]
//                 [--pinhole FOV[,WxH]] [--equirect W] [--sampling nearest|bilinear]
// curvestereo run --calib CALIB --sequence SRC -o OUTDIR [--poses FILE] [--cold] [...]:
//                 each frame's outputs into OUTDIR/<t_ns>/
// curvestereo run --calib CALIB --log FILE --topics LEFT,RIGHT -o OUT.mcap|OUTDIR [...]:
//                 a recorded log's frames, the same way; depth into an MCAP log or folders
#include <unistd.h>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/depth_views.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/log.hpp"
#include "curvestereo/sequence.hpp"
#include "rig_cli.hpp"

namespace cs::cli {

namespace {

// The rig options a pair's run refuses: every rig command's and run's own (and --rig, where
// it cannot make the run a rig's).
std::vector<std::string> rigOnlyOptions(bool withRig) {
  std::vector<std::string> out(kRigOptions.begin(), kRigOptions.end());
  out.push_back("panorama-width");
  if (withRig) out.push_back("rig");
  return out;
}

// The extra depth forms for other tools (docs/guide.md "Outputs for ROS, Open3D and mapping").
struct ViewOptions {
  bool pinhole = false;
  PinholeView view;
  int equirectWidth = 0;  // 0: none
  DepthSampling sampling = DepthSampling::Nearest;
};

// "FOV" or "FOV,WxH"; the size defaults to camera 0's.
PinholeView parsePinhole(const std::string& text, const Camera& cam0) {
  const std::string usage =
      "--pinhole expects FOV[,WxH] (horizontal degrees, e.g. 90 or 90,640x480), got '" + text + "'";
  const size_t comma = text.find(',');
  const std::string fovText = text.substr(0, comma);
  char* end = nullptr;
  const double fov = std::strtod(fovText.c_str(), &end);
  if (fovText.empty() || *end != 0 || !std::isfinite(fov)) throw Error(usage);
  int w = cam0.width, h = cam0.height;
  if (comma != std::string::npos) {
    const std::string size = text.substr(comma + 1);
    const size_t x = size.find('x');
    if (x == std::string::npos || !wholeNumber(size.substr(0, x), w) || !wholeNumber(size.substr(x + 1), h))
      throw Error(usage);
  }
  return PinholeView::fromFov(fov, w, h);
}

ViewOptions viewOptions(const Args& args, const Camera& cam0) {
  ViewOptions v;
  if (args.has("pinhole")) {
    v.pinhole = true;
    v.view = parsePinhole(args.get("pinhole", ""), cam0);
  }
  if (args.has("equirect")) {
    const std::string text = args.get("equirect", "");
    if (!wholeNumber(text, v.equirectWidth) || v.equirectWidth < 4 || v.equirectWidth % 2 || v.equirectWidth > 32768)
      throw Error("--equirect expects an even width of 4 to 32768 px (the image is W x W/2), got '" + text + "'");
  }
  const std::string sampling = args.get("sampling", "nearest");
  if (sampling != "nearest" && sampling != "bilinear")
    throw Error("--sampling expects nearest or bilinear, got '" + sampling + "'");
  v.sampling = sampling == "bilinear" ? DepthSampling::Bilinear : DepthSampling::Nearest;
  return v;
}

// points.pcd (always, beside points.ply), and the pinhole / equirectangular views asked for.
void writeViews(const std::string& dir, const ViewOptions& v, const Camera& cam0, const DepthResult& r,
                float minConfidence) {
  auto path = [&](const char* name) { return (std::filesystem::path(dir) / name).string(); };
  writeOrganisedCloud(dir, r, minConfidence);
  if (v.pinhole) {
    const ImageF z = pinholeDepth(cam0, r.depth.radial, v.view, v.sampling);
    writeExr(path("depth_pinhole.exr"), z);
    writeDepthPngMillimetres(path("depth_pinhole.png"), z);
    writeCameraInfoYaml(path("camera_info.yaml"), v.view, "curvestereo_pinhole");
    std::printf("pinhole: %dx%d, fx = fy = %.6g px: depth_pinhole.exr, depth_pinhole.png, camera_info.yaml\n",
                v.view.width, v.view.height, v.view.fx);
  }
  if (v.equirectWidth) {
    writeExr(path("range_equirect.exr"), equirectRange(cam0, r.depth.radial, v.equirectWidth, v.sampling));
    std::printf("equirectangular: %dx%d: range_equirect.exr\n", v.equirectWidth, v.equirectWidth / 2);
  }
}

// -o names a folder for the outputs: an existing file there is refused before any work
// (writing the outputs would fail only after the solve).
void requireOutputFolder(const std::string& dir) {
  std::error_code ec;
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec))
    throw Error("-o " + dir + ": is an existing file, not a folder for the outputs");
}

// Frames per second and counts, one line, in place on a terminal.
struct SequenceTally {
  int frames = 0, warm = 0, cold = 0, redone = 0;
  double solveMs = 0, warmMs = 0, coldMs = 0;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  void add(const DepthResult& r) {
    ++frames;
    solveMs += r.totalMs;
    (r.warm ? warm : cold) += 1;
    (r.warm ? warmMs : coldMs) += r.totalMs;
    redone += r.redone;
  }
  double wallSeconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); }
};

// "-o OUT.mcap": the depth goes into one MCAP log (DepthLogWriter) instead of folders.
bool mcapOutput(const std::string& out) { return out.size() > 5 && out.compare(out.size() - 5, 5, ".mcap") == 0; }

// --log FILE --topics LEFT,RIGHT, or --sequence SRC: the frames and the calibration's path.
Sequence openFrames(const Args& args, std::string& calibPath) {
  SequenceOptions options;
  options.poses = args.get("poses", "");
  options.pairToleranceMs = args.getDouble("pair-tolerance-ms", options.pairToleranceMs);
  if (!args.has("log")) {
    const std::string source = args.get("sequence", "");
    calibPath = sequenceCalibration(args, source);
    return Sequence::open(source, options);
  }
  calibPath = args.require("calib");  // a log holds no calibration we read
  const std::string topics = args.require("topics");
  const size_t comma = topics.find(',');
  if (comma == std::string::npos || topics.find(',', comma + 1) != std::string::npos || comma == 0 ||
      comma + 1 == topics.size())
    throw UsageError("--topics expects LEFT,RIGHT (two topic names), got '" + topics + "'");
  return Sequence::openLog(args.get("log", ""), topics.substr(0, comma), topics.substr(comma + 1), options);
}

// run --sequence / --log: every frame through Stereo::next (warm start and temporal filter
// unless --cold), each frame's outputs in OUT/<t_ns>/ under a pair run's names, or into the
// MCAP log OUT.mcap. A frame that cannot be read or solved stops the run with one line naming
// it; the frames before stay written (the MCAP log is closed with them).
int runSequence(const Args& args, const std::string& outDir) {
  std::string calibPath;
  const Sequence sequence = openFrames(args, calibPath);
  const auto [first, end] = frameRange(args, sequence.frames().size());  // checked before any output
  const size_t total = end - first;
  for (const std::string& w : sequence.warnings()) std::fprintf(stderr, "curvestereo: warning: %s\n", w.c_str());
  Params params = paramsFromArgs(args);
  const bool cold = args.has("cold");
  if (cold) params.warmStart = false, params.temporalStrength = 0.f;  // every frame alone: the baseline
  const float minConfidence = minConfidenceFromArgs(args);
  const Rig rig = loadCalibration(calibPath, nullptr, calibHintsFromArgs(args));
  const ViewOptions views = viewOptions(args, rig.cam0);
  Stereo stereo(rig, params, backendFromArgs(args));
  if (args.has("mask")) stereo.setMask(loadMask(args.get("mask", "")));
  std::unique_ptr<DepthLogWriter> log;
  if (mcapOutput(outDir)) {
    if (args.has("equirect")) throw UsageError("--equirect is for folder outputs, not an MCAP log");
    DepthLogOptions o;
    o.compression = args.get("compression", "zstd");
    o.minConfidence = minConfidence;
    o.pinhole = views.pinhole;
    o.pinholeView = views.view;
    o.sampling = views.sampling;
    log = std::make_unique<DepthLogWriter>(outDir, rig, o);
  }
  std::printf("sequence: %s\n", sequence.summary().c_str());
  std::printf("backend: %s (%s) - %s\n", stereo.backendName().c_str(), stereo.deviceName().c_str(),
              stereo.backendChoice().c_str());
  std::printf("settings: %s; %s\n", describe(params).c_str(),
              cold ? "cold: every frame solved alone" : "warm start and temporal filter");
  const bool tty = isatty(fileno(stderr));
  SequenceTally tally;
  ImageF left, right;
  DepthResult r;
  const std::vector<SequenceFrame>& frames = sequence.frames();
  // Frames are read ahead on background threads while this one solves (its wait is reported).
  SequenceReader reader(sequence, readThreads(args), first, end);
  while (true) {
    size_t i = 0;
    const std::string written = " (" + std::to_string(tally.frames) + " frames before it are written)";
    try {
      if (!reader.next(i, left, right)) break;  // a frame's error names the frame
    } catch (const Error& e) {
      if (tty) std::fputc('\n', stderr);
      throw Error(e.what() + written);
    }
    const SequenceFrame& f = frames[i];
    const std::string name = std::to_string(f.timestampNs);
    try {
      stereo.next(left, right, r, f.hasPose ? &f.pose : nullptr);
      if (log) {
        log->write(f.timestampNs, r);
      } else {
        const std::string dir = (std::filesystem::path(outDir) / name).string();
        writeOutputs(dir, r, left, minConfidence);
        writeViews(dir, views, rig.cam0, r, minConfidence);
      }
    } catch (const Error& e) {
      if (tty) std::fputc('\n', stderr);
      throw Error("frame " + std::to_string(i) + " (t " + name + " ns): " + e.what() + written);
    }
    tally.add(r);
    const double fps = tally.frames / std::max(1e-9, tally.wallSeconds());
    if (tty || tally.frames == int(total) || tally.frames % 30 == 0)
      std::fprintf(stderr, "%sframe %d/%zu  %s%s  %.1f ms  %.1f frames/s%s", tty ? "\r" : "", tally.frames, total,
                   r.warm ? "warm" : "cold", r.redone ? " (warm failed, redone)" : "", r.totalMs, fps,
                   tty ? "   " : "\n");
  }
  if (tty) std::fputc('\n', stderr);
  if (log) log->close();
  auto mean = [](double ms, int n) { return n ? ms / n : 0.0; };
  std::printf(
      "%d frames in %.1f s: %.2f ms a frame solved (warm %d, %.2f ms; cold %d, %.2f ms; %d warm frames "
      "redone cold); outputs in %s%s\n",
      tally.frames, tally.wallSeconds(), mean(tally.solveMs, tally.frames), tally.warm, mean(tally.warmMs, tally.warm),
      tally.cold, mean(tally.coldMs, tally.cold), tally.redone, outDir.c_str(), log ? "" : "/<t_ns>/");
  std::printf(
      "read: %.3f ms a frame on %d reader thread%s ahead; the solving thread waited %.1f ms for the first frame, "
      "%.3f ms a frame for the others\n",
      mean(reader.readMs(), tally.frames), reader.threads(), reader.threads() == 1 ? "" : "s", reader.firstWaitMs(),
      mean(reader.waitedMs(), tally.frames - 1));
  return 0;
}

}  // namespace

int cmdRun(const Args& args) {
  std::set<std::string> known = kSolverOptions;
  known.insert(
      {"min-confidence", "calib", "o", "output", "scale-intrinsics", "pinhole", "equirect", "sampling", "image-size"});
  known.insert({"rig", "panorama-width"});
  known.insert(kRigOptions.begin(), kRigOptions.end());
  known.insert(
      {"sequence", "poses", "cold", "pair-tolerance-ms", "log", "topics", "compression", "read-threads", "frames"});
  args.allowOnly(known);
  if (args.has("sequence") && args.has("log")) throw UsageError("give --sequence or --log, not both");
  if (args.has("sequence") || args.has("log")) {
    const char* which = args.has("log") ? "run --log" : "run --sequence";
    if (!args.positional().empty()) throw UsageError(std::string(which) + " takes no images: the source names them");
    for (const char* option : {"topics", "compression"})
      if (args.has(option) && !args.has("log")) throw UsageError(std::string("--") + option + " is for run --log");
    if (args.has("sequence") && isRigSequence(args)) {
      for (const char* option :
           {"pinhole", "equirect", "sampling", "scale-intrinsics", "image-size", "mask", "read-threads"})
        if (args.has(option)) throw UsageError(std::string("--") + option + " is for a pair, not a rig's sequence");
      const std::string outDir = args.has("o") ? args.get("o", "") : args.require("output");
      requireOutputFolder(outDir);
      return runRigSequence(args, outDir);
    }
    for (const std::string& option : rigOnlyOptions(true))
      if (args.has(option))
        throw UsageError(std::string("--") + option + " is for a rig: " + which +
                         " solves a pair (a rig's sequence: --sequence DIR --rig)");
    const std::string outDir = args.has("o") ? args.get("o", "") : args.require("output");
    if (!mcapOutput(outDir)) requireOutputFolder(outDir);
    if (args.has("compression") && !mcapOutput(outDir)) throw UsageError("--compression is for -o OUT.mcap");
    return runSequence(args, outDir);
  }
  for (const char* option : {"poses", "cold", "pair-tolerance-ms", "topics", "compression", "read-threads", "frames"})
    if (args.has(option)) throw UsageError(std::string("--") + option + " is for run --sequence or --log");
  // Three images or more, or --rig: a rig of as many cameras (cmd_rig.cpp).
  if (args.positional().size() >= 3 || args.has("rig")) {
    const std::string outDir = args.has("o") ? args.get("o", "") : args.require("output");
    requireOutputFolder(outDir);
    for (const char* option : {"pinhole", "equirect", "sampling", "scale-intrinsics", "image-size", "mask"})
      if (args.has(option)) throw UsageError(std::string("--") + option + " is for a pair, not a rig of cameras");
    return runRig(args, outDir);
  }
  for (const std::string& option : rigOnlyOptions(false))
    if (args.has(option))
      throw UsageError(std::string("--") + option + " is for a rig (three images or more, or --rig)");
  if (args.positional().size() != 2)
    throw UsageError("run needs exactly two images: LEFT RIGHT (or one per camera of a rig: IMG0 IMG1 IMG2 ...)");
  const std::string outDir = args.has("o") ? args.get("o", "") : args.require("output");
  requireOutputFolder(outDir);
  const Params params = paramsFromArgs(args);
  const float minConfidence = minConfidenceFromArgs(args);
  const StereoInputs in =
      loadStereoInputs(args.require("calib"), args.positional()[0], args.positional()[1], args.has("scale-intrinsics"));
  const Rig& rig = in.rig;
  const ImageF& left = in.left;
  const ImageF& right = in.right;
  const ViewOptions views = viewOptions(args, rig.cam0);  // checked before the solve, not after

  Stereo stereo(rig, params, backendFromArgs(args));
  if (args.has("mask")) stereo.setMask(loadMask(args.get("mask", "")));
  std::printf("backend: %s (%s) - %s\n", stereo.backendName().c_str(), stereo.deviceName().c_str(),
              stereo.backendChoice().c_str());
  std::printf("settings: %s\n", describe(params).c_str());
  stereo.setProfiling(true);  // one frame: the stage breakdown is worth a synchronisation
  Progress progress("solving");
  stereo.setProgress([&](double f) { progress(f); });
  DepthResult r = stereo.compute(left, right);
  progress.done();
  writeOutputs(outDir, r, left, minConfidence);
  writeViews(outDir, views, rig.cam0, r, minConfidence);

  long long valid = 0;
  for (auto v : r.valid.data) valid += v;
  std::printf("stages: %s\n", formatStages(r.stages).c_str());
  std::printf("total %.1f ms, %lld valid pixels (%.1f %% of the image); outputs in %s\n", r.totalMs, valid,
              100.0 * double(valid) / double(r.valid.size()), outDir.c_str());
  if (stereo.params().lrCheck)
    std::printf("lr-check: %.1f %% of the pixels in the field of view passed the round trip (%g px)\n",
                100.0 * r.lrPassShare, stereo.params().lrCheckPx);
  return 0;
}

}  // namespace cs::cli

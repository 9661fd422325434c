// curvestereo bench [--calib CAMCHAIN LEFT RIGHT | --size WxH] [--runs N]: time per
// frame and per stage after a warm-up frame, in the manner of libSGM's benchmark.
// curvestereo bench --sequence SRC [--calib C] [--runs N]: a sequence's frames through
// Stereo::next, warm and cold frames timed apart.
// curvestereo bench --calib RIG IMG0 IMG1 IMG2 ...: a rig's frames, solves and panorama
// (cmd_rig.cpp).
#include <algorithm>
#include <cstdio>
#include <functional>
#include <map>

#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/sequence.hpp"
#include "rig_cli.hpp"
#include "synth/scene.hpp"

namespace cs::cli {

namespace {

struct Inputs {
  Rig rig;
  ImageF left, right;
  std::string what;
  // The files' 8-bit samples as stored, when both are 8-bit gray PNGs at the calibration's
  // size: what a camera gives, timed as Stereo takes it (a quarter of the bytes to move), as
  // bench --sequence does. Empty otherwise (16-bit or colour files, scaled intrinsics).
  ImageU8 leftBytes, rightBytes;
  bool bytes() const { return !leftBytes.data.empty(); }
};

// Both files' bytes when both are 8-bit gray and the images' sizes are the solve's.
void readBytesIfEightBit(const std::string& leftPath, const std::string& rightPath, Inputs& in) {
  ImageU8 l, r;
  readPngGray(leftPath, nullptr, &l);
  readPngGray(rightPath, nullptr, &r);
  const bool sized = l.width == in.left.width && l.height == in.left.height && r.width == in.right.width &&
                     r.height == in.right.height;
  if (!l.data.empty() && !r.data.empty() && sized) in.leftBytes = std::move(l), in.rightBytes = std::move(r);
}

void computeInputs(Stereo& stereo, const Inputs& in, DepthResult& result) {
  if (in.bytes())
    stereo.compute(in.leftBytes, in.rightBytes, result);
  else
    stereo.compute(in.left, in.right, result);
}

Inputs benchInputs(const Args& args) {
  if (args.has("calib")) {
    if (args.positional().size() != 2) throw UsageError("bench --calib needs LEFT RIGHT images");
    StereoInputs loaded = loadStereoInputs(args.require("calib"), args.positional()[0], args.positional()[1],
                                           args.has("scale-intrinsics"));
    Inputs in{std::move(loaded.rig), std::move(loaded.left), std::move(loaded.right), args.require("calib"), {}, {}};
    readBytesIfEightBit(args.positional()[0], args.positional()[1], in);
    return in;
  }
  // A synthetic pair of the requested size (same default fisheye as the demo).
  int w = 800, h = 800;
  std::string size = args.get("size", "800x800");
  if (std::sscanf(size.c_str(), "%dx%d", &w, &h) != 2 || w < 16 || h < 16 || w > 16384 || h > 16384)
    throw Error("option --size expects WxH (e.g. 848x800), got '" + size + "'");
  synth::SynthConfig cfg;
  cfg.camera = synth::defaultFisheye(std::max(w, h));
  cfg.camera.width = w;
  cfg.camera.height = h;
  cfg.camera.params[2] = 0.5 * (w - 1);
  cfg.camera.params[3] = 0.5 * (h - 1);
  cfg.samplesPerAxis = 1;
  synth::SynthPair pair = synth::renderPair(cfg);
  return {pair.rig, pair.left, pair.right, "synthetic " + size, {}, {}};
}

void printStageTable(const std::vector<std::string>& order, std::map<std::string, std::vector<double>>& perStage,
                     const std::vector<double>& sweepTotals) {
  std::printf("%-20s %10s %10s %10s\n", "stage", "median ms", "min", "max");
  for (const std::string& name : order) {
    Summary s = summarize(perStage[name]);
    std::printf("%-20s %10.2f %10.2f %10.2f\n", name.c_str(), s.median, s.min, s.max);
  }
  // The plane sweep is several stages (the coarse and the band sweep, both views, the
  // checks); its total a frame is what the sweep costs.
  if (!sweepTotals.empty()) {
    Summary s = summarize(sweepTotals);
    std::printf("%-20s %10.2f %10.2f %10.2f\n", "sweep, all stages", s.median, s.min, s.max);
  }
}

// The stage times of one frame into the table's columns.
void collectStages(const DepthResult& r, std::map<std::string, std::vector<double>>& perStage,
                   std::vector<std::string>& order, std::vector<double>& sweepTotals) {
  double sweepMs = 0.0;
  bool swept = false;
  for (const StageTime& s : r.stages) {
    if (!perStage.count(s.name)) order.push_back(s.name);
    perStage[s.name].push_back(s.ms);
    if (s.name.rfind("sweep", 0) == 0) sweepMs += s.ms, swept = true;
  }
  if (swept) sweepTotals.push_back(sweepMs);
}

// The frames as their files store them: a camera's 8-bit images go to Stereo as bytes.
struct HeldFrames {
  std::vector<ImageF> lefts, rights;
  std::vector<ImageU8> leftBytes, rightBytes;
  bool bytes = true;

  explicit HeldFrames(const Sequence& sequence) {
    const size_t n = sequence.frames().size();
    leftBytes.resize(n), rightBytes.resize(n);
    for (size_t i = 0; i < n && bytes; ++i) bytes = sequence.loadBytes(i, leftBytes[i], rightBytes[i]);
    if (bytes) return;
    leftBytes.clear(), rightBytes.clear();
    lefts.resize(n), rights.resize(n);
    for (size_t i = 0; i < n; ++i) sequence.load(i, lefts[i], rights[i]);
  }
  void next(Stereo& stereo, size_t i, DepthResult& r, const Pose* pose) const {
    if (bytes)
      stereo.next(leftBytes[i], rightBytes[i], r, pose);
    else
      stereo.next(lefts[i], rights[i], r, pose);
  }
};

// bench --sequence: every frame held in memory, then `runs` passes through Stereo::next
// (each from a reset: a cold first frame, warm ones after), after one pass that records
// every kind of frame; a last pass profiles the warm frames' stages.
int benchSequence(const Args& args, Stereo& stereo, const Sequence& sequence, int runs) {
  const std::vector<SequenceFrame>& frames = sequence.frames();
  const HeldFrames held(sequence);
  std::printf("input:    sequence %s; %s\n", sequence.summary().c_str(),
              held.bytes ? "8-bit images, passed as bytes" : "images passed as floats");
  std::printf("runs:     %d passes of %zu frames after 1 warm-up pass\n", runs, frames.size());
  DepthResult r;
  auto pass = [&](bool profiled, const std::function<void(const DepthResult&)>& each) {
    stereo.setProfiling(profiled);
    stereo.resetSequence();
    for (size_t i = 0; i < frames.size(); ++i) {
      held.next(stereo, i, r, frames[i].hasPose ? &frames[i].pose : nullptr);
      each(r);
    }
  };
  pass(false, [](const DepthResult&) {});
  std::vector<double> warm, cold, sweepTotals;
  int redone = 0;
  Progress progress("benchmark");
  for (int k = 0; k < runs; ++k) {
    pass(false, [&](const DepthResult& f) {
      (f.warm ? warm : cold).push_back(f.totalMs);
      redone += f.redone;
    });
    progress(double(k + 1) / runs);
  }
  progress.done();
  std::map<std::string, std::vector<double>> perStage;
  std::vector<std::string> order;
  pass(true, [&](const DepthResult& f) {
    if (f.warm) collectStages(f, perStage, order, sweepTotals);
  });
  (void)args;
  for (auto [name, times] : {std::pair{"warm", &warm}, std::pair{"cold", &cold}}) {
    if (times->empty()) {
      std::printf("%s:     no frames\n", name);
      continue;
    }
    const Summary s = summarize(*times);
    std::printf(
        "%s:     median %.2f ms  min %.2f  max %.2f  (%.1f fps) over %zu frames, end to end into a reused "
        "DepthResult\n",
        name, s.median, s.min, s.max, 1000.0 / s.median, times->size());
  }
  std::printf("redone:   %d warm frames failed their check and were solved again cold\n", redone);
  std::printf("warm frames, profiled (synchronised at each stage):\n");
  printStageTable(order, perStage, sweepTotals);
  return 0;
}

}  // namespace

int cmdBench(const Args& args) {
  std::set<std::string> known = kSolverOptions;
  known.insert(
      {"calib", "size", "runs", "scale-intrinsics", "outputs", "sequence", "poses", "panorama-width", "serial"});
  known.insert(kRigOptions.begin(), kRigOptions.end());
  args.allowOnly(known);
  if (args.has("runs") && args.getInt("runs", 0) < 1) throw Error("option --runs must be >= 1");
  // Three images or more: a rig of as many cameras (cmd_rig.cpp), as for run.
  if (args.positional().size() >= 3 && !args.has("sequence")) return benchRig(args);
  std::vector<std::string> rigOnly(kRigOptions.begin(), kRigOptions.end());
  rigOnly.insert(rigOnly.end(), {"panorama-width", "serial"});
  for (const std::string& option : rigOnly)
    if (args.has(option)) throw UsageError(std::string("--") + option + " is for a rig (three images or more)");
  const Params params = paramsFromArgs(args);
  if (args.has("sequence")) {
    if (!args.positional().empty()) throw UsageError("bench --sequence takes no images: the sequence names them");
    SequenceOptions options;
    options.poses = args.get("poses", "");
    const Sequence sequence = Sequence::open(args.get("sequence", ""), options);
    for (const std::string& w : sequence.warnings()) std::fprintf(stderr, "curvestereo: warning: %s\n", w.c_str());
    Stereo stereo(loadCalibration(sequenceCalibration(args, args.get("sequence", ""))), params, backendFromArgs(args));
    if (args.get("outputs", "depth") == "depth") stereo.setOutputs({false, false, false, false});
    std::printf("device:   %s (backend %s)\n", stereo.deviceName().c_str(), stereo.backendName().c_str());
    std::printf("settings: %s\n", describe(params).c_str());
    return benchSequence(args, stereo, sequence, args.getInt("runs", stereo.backendName() == "cpu" ? 1 : 5));
  }
  const Inputs in = benchInputs(args);
  Stereo stereo(in.rig, params, backendFromArgs(args));
  // A GPU frame takes milliseconds: 50 of them give a stable median. The CPU oracle takes
  // seconds per frame, so it defaults to a few.
  const int runs = args.getInt("runs", stereo.backendName() == "cpu" ? 3 : 50);
  // By default a frame is what a depth application needs: images up, depth back (the valid
  // mask is derived from it). --outputs all adds disparity, warp, points and the initialiser's
  // confidence (and their transfers).
  const std::string outputs = args.get("outputs", "depth");
  if (outputs != "depth" && outputs != "all")
    throw Error("option --outputs expects depth or all, got '" + outputs + "'");
  if (outputs == "depth") stereo.setOutputs({false, false, false, false});

  std::printf("device:   %s (backend %s)\n", stereo.deviceName().c_str(), stereo.backendName().c_str());
  std::printf("input:    %s, %dx%d, %s\n", in.what.c_str(), in.left.width, in.left.height,
              in.bytes() ? "8-bit samples as stored" : "float");
  std::printf("settings: %s\n", describe(params).c_str());
  std::printf("outputs:  %s\n",
              outputs == "depth" ? "radial depth + valid mask" : "all (depth, disparity, warp, points, confidence)");
  std::printf("buffers:  %.0f MB per frame\n", double(stereo.bufferBytes()) / 1e6);
  std::printf("runs:     %d after 1 warm-up frame\n", runs);
  // Frames as a real-time application runs them: into the same DepthResult every frame,
  // so its images are allocated once (here, by the warm-up frame: first-touch allocation,
  // caches) and GPU backends replay a recorded frame.
  DepthResult result;
  computeInputs(stereo, in, result);

  // Then the same number through compute() returning a new DepthResult (allocated and
  // zero-filled each frame), and the same number with per-stage timing, which
  // synchronises at every stage boundary.
  std::vector<double> totals, byValueTotals, profiledTotals, sweepTotals;
  std::map<std::string, std::vector<double>> perStage;
  std::vector<std::string> order;
  Progress progress("benchmark");
  for (int i = 0; i < 3 * runs; ++i) {
    const bool byValue = i >= runs && i < 2 * runs, profiled = i >= 2 * runs;
    stereo.setProfiling(profiled);
    if (byValue) {
      DepthResult r;
      computeInputs(stereo, in, r);
      byValueTotals.push_back(r.totalMs);
    } else {
      computeInputs(stereo, in, result);
      (profiled ? profiledTotals : totals).push_back(result.totalMs);
      collectStages(result, perStage, order, sweepTotals);
    }
    progress(double(i + 1) / (3 * runs));
  }
  progress.done();
  Summary t = summarize(totals), tv = summarize(byValueTotals), tp = summarize(profiledTotals);
  std::printf(
      "\nframe:    median %.2f ms  min %.2f  max %.2f  (%.1f fps), end to end incl. upload, download, triangulation, "
      "into a reused DepthResult\n",
      t.median, t.min, t.max, 1000.0 / t.median);
  std::printf("by value: median %.2f ms (compute returning a new DepthResult each frame)\n", tv.median);
  std::printf("profiled: median %.2f ms (synchronised at each stage)\n", tp.median);
  printStageTable(order, perStage, sweepTotals);
  return 0;
}

}  // namespace cs::cli

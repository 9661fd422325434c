// `eval --sequence DIR...`: a recorded sequence with ground truth (ASL layout, as
// ../shared/data/sequences/README.md describes it) run frame after frame through
// Stereo::next, warm (the default) or --cold (every frame solved on its own), or both with
// --compare; per frame tau>1 / tau>3 (all and non-occluded), tau>1 on the moving object's
// pixels and the flicker against the previous frame (docs/accuracy.md "How accuracy is measured",
// *sequences*; metrics.hpp maskedTau / flicker), then a summary per run.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "common.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/metrics.hpp"
#include "curvestereo/sequence.hpp"
#include "eval.hpp"

namespace cs::cli::eval {

namespace {

namespace fs = std::filesystem;

const double kNaN = std::numeric_limits<double>::quiet_NaN();
// A ground-truth file belongs to a frame when its timestamp is within this of the frame's
// (as SequenceOptions::pairToleranceMs pairs the two cameras).
constexpr int64_t kGroundTruthToleranceNs = 1000000;

// --- the sequence and its ground truth ---

// One ground-truth stream of an ASL folder (mav0/depth0, depth1, mover0): timestamp -> file.
struct Stream {
  std::string name;  // "depth0"
  std::map<int64_t, std::string> files;
  bool present() const { return !files.empty(); }
  // The file of the frame at t; "" when the stream has none within the tolerance.
  std::string at(int64_t t) const {
    auto it = files.lower_bound(t - kGroundTruthToleranceNs);
    return it != files.end() && it->first <= t + kGroundTruthToleranceNs ? it->second : std::string();
  }
};

// The stream's data.csv, or, without one, the files of its data/ folder named <t>.<ext>.
// An absent folder gives an empty stream.
Stream readStream(const fs::path& mav0, const char* name) {
  Stream s{name, {}};
  const fs::path dir = mav0 / name, csv = dir / "data.csv";
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return s;
  if (fs::is_regular_file(csv, ec)) {
    std::ifstream f(csv, std::ios::binary);
    std::stringstream text;
    text << f.rdbuf();
    if (!f) throw Error("cannot read '" + csv.string() + "'");
    for (const AslRow& row : parseAslCsv(text.str(), csv.string()))
      s.files[row.timestampNs] = (dir / "data" / row.filename).string();
  } else {
    for (const fs::directory_entry& e : fs::directory_iterator(dir / "data", ec)) {
      const std::string stem = e.path().stem().string();
      char* end = nullptr;
      const long long t = std::strtoll(stem.c_str(), &end, 10);
      if (!stem.empty() && end && !*end) s.files[t] = e.path().string();
    }
  }
  if (s.files.empty()) throw Error("'" + dir.string() + "' lists no files (no data.csv rows, no data/<t>.* files)");
  return s;
}

struct SequenceInput {
  std::string dir, name;
  Sequence seq;
  Rig rig;
  fs::path mav0;
  Stream depth0, depth1, mover0;
  size_t frames = 0;  // evaluated: the first `frames` of seq
};

std::string folderName(const std::string& dir) {
  const fs::path norm = fs::path(dir).lexically_normal();
  const std::string name = norm.filename().string();
  return name.empty() ? norm.parent_path().filename().string() : name;
}

SequenceInput openSequence(const std::string& dir, const Args& args, int maxFrames) {
  SequenceInput in{dir, folderName(dir), Sequence::open(dir), {}, {}, {}, {}, {}, 0};
  std::error_code ec;
  in.mav0 = fs::path(dir) / "mav0";
  if (!fs::is_directory(in.mav0 / "cam0", ec)) in.mav0 = dir;  // dir is mav0/ itself
  if (in.name == "mav0") in.name = folderName(fs::path(dir).lexically_normal().parent_path().string());
  if (!fs::is_directory(in.mav0 / "cam0", ec))
    throw Error("eval --sequence: '" + dir +
                "' is not an ASL folder (mav0/cam0/): ground truth is read from mav0/depth0");
  in.rig = loadCalibration(sequenceCalibration(args, dir));
  in.depth0 = readStream(in.mav0, "depth0");
  if (!in.depth0.present())
    throw Error("sequence '" + dir + "' has no ground truth: no mav0/depth0/ (camera 0's depth maps)");
  in.depth1 = readStream(in.mav0, "depth1");
  in.mover0 = readStream(in.mav0, "mover0");
  in.frames = in.seq.frames().size();
  if (maxFrames > 0 && size_t(maxFrames) < in.frames) in.frames = size_t(maxFrames);
  // Every frame's camera 0 depth is checked here, not after minutes of solving.
  for (size_t i = 0; i < in.frames; ++i) {
    const int64_t t = in.seq.frames()[i].timestampNs;
    for (const Stream* s : {&in.depth0, &in.depth1, &in.mover0}) {
      if (!s->present()) continue;
      const std::string path = s->at(t);
      if (path.empty())
        throw Error("sequence '" + dir + "' frame " + std::to_string(i) + " (t " + std::to_string(t) + " ns): no " +
                    s->name + " file within 1 ms");
      if (!fs::is_regular_file(path, ec))
        throw Error("sequence '" + dir + "' frame " + std::to_string(i) + ": missing " + s->name + " file '" + path +
                    "'");
    }
  }
  return in;
}

// One frame's ground truth: camera 0's and (when present) camera 1's depth, the mover mask.
struct FrameTruth {
  ImageF depth0, depth1;
  ImageU8 mover;  // empty without mover0
};

FrameTruth loadTruth(const SequenceInput& in, size_t i) {
  const int64_t t = in.seq.frames()[i].timestampNs;
  const Camera& cam = in.rig.cam0;
  auto sized = [&](auto image, const std::string& path) {
    if (image.width != cam.width || image.height != cam.height)
      throw Error("'" + path + "' is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                  ", the calibration " + std::to_string(cam.width) + "x" + std::to_string(cam.height));
    return image;
  };
  FrameTruth gt;
  gt.depth0 = sized(readExr(in.depth0.at(t)), in.depth0.at(t));
  if (in.depth1.present()) gt.depth1 = sized(readExr(in.depth1.at(t)), in.depth1.at(t));
  if (in.mover0.present()) {
    const ImageF m = sized(readPngGray(in.mover0.at(t)), in.mover0.at(t));
    gt.mover = ImageU8(m.width, m.height);
    for (size_t k = 0; k < m.size(); ++k) gt.mover.data[k] = m.data[k] > 0.5f;
  }
  return gt;
}

// --- a run ---

struct FrameRow {
  int64_t timestampNs = 0;
  bool warm = false, redone = false;
  Metrics m;
  double tau1Mover = kNaN;
  long long moverPixels = 0;
  double flicker = kNaN;  // against the previous frame; NaN for the first or without poses
  long long flickerPoints = 0;
  double ms = 0;
  const char* state() const { return redone ? "redone" : warm ? "warm" : "cold"; }
};

struct Run {
  std::string sequence, mode;  // mode: "warm" or "cold"
  std::vector<FrameRow> frames;
};

struct Summary {
  double tau1 = kNaN, tau3 = kNaN, tau1Noc = kNaN, tau1Mover = kNaN, flicker = kNaN, absRel = kNaN, density = kNaN,
         ms = kNaN;
  int warm = 0, cold = 0, redone = 0, moverFrames = 0, flickerPairs = 0;
};

// Mean of the finite values (NaN when none); n (optional) receives their number.
template <class Get>
double meanOf(const std::vector<FrameRow>& rows, Get get, int* n = nullptr) {
  double sum = 0;
  int k = 0;
  for (const FrameRow& r : rows)
    if (std::isfinite(get(r))) sum += get(r), ++k;
  if (n) *n = k;
  return k ? sum / k : kNaN;
}

Summary summarize(const Run& run) {
  Summary s;
  const auto& f = run.frames;
  s.tau1 = meanOf(f, [](const FrameRow& r) { return r.m.tau1; });
  s.tau3 = meanOf(f, [](const FrameRow& r) { return r.m.tau3; });
  s.tau1Noc = meanOf(f, [](const FrameRow& r) { return r.m.tau1Noc; });
  s.tau1Mover = meanOf(
      f, [](const FrameRow& r) { return r.tau1Mover; }, &s.moverFrames);
  s.flicker = meanOf(
      f, [](const FrameRow& r) { return r.flicker; }, &s.flickerPairs);
  s.absRel = meanOf(f, [](const FrameRow& r) { return r.m.absRel; });
  s.density = meanOf(f, [](const FrameRow& r) { return r.m.density; });
  s.ms = meanOf(f, [](const FrameRow& r) { return r.ms; });
  for (const FrameRow& r : f) (r.redone ? s.redone : r.warm ? s.warm : s.cold)++;
  return s;
}

// The progress line on stderr: rewritten in place on a terminal, one line per frame otherwise.
void progressLine(const Run& run, size_t done, size_t total, double wallS, bool last) {
  static const bool tty = isatty(fileno(stderr));
  if (!tty && !last && done % 10 != 1 && done != total) return;  // a log gets a line now and then
  double solveMs = 0;
  for (const FrameRow& r : run.frames) solveMs += r.ms;
  std::fprintf(stderr, "%s%s %s: frame %zu/%zu  %.2f fps (solve %.0f ms/frame)%s", tty ? "\r" : "",
               run.sequence.c_str(), run.mode.c_str(), done, total, wallS > 0 ? double(done) / wallS : 0.0,
               done ? solveMs / double(done) : 0.0, tty && !last ? "" : "\n");
  std::fflush(stderr);
}

Run runSequence(const SequenceInput& in, Params params, const std::string& backend, const std::string& mode,
                const Args& args) {
  if (mode == "cold") {
    params.warmStart = false;
    params.temporalStrength = 0;
  }
  Stereo stereo(in.rig, params, backend);
  if (args.has("mask")) stereo.setMask(loadMask(args.get("mask", "")));
  Stereo::Outputs outputs;
  outputs.disparity = outputs.points = outputs.confidence = false;  // the warp and the depth suffice
  stereo.setOutputs(outputs);
  std::fprintf(stderr, "%s %s: %zu frames, backend %s (%s)\n", in.name.c_str(), mode.c_str(), in.frames,
               stereo.backendName().c_str(), stereo.deviceName().c_str());

  Run run{in.name, mode, {}};
  ImageF left, right, estPrev, gtPrev;
  ImageU8 moverPrev;
  const SequenceFrame* prev = nullptr;
  DepthResult r;
  const auto t0 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < in.frames; ++i) {
    const SequenceFrame& f = in.seq.frames()[i];
    in.seq.load(i, left, right);
    FrameTruth gt = loadTruth(in, i);
    // --blind: the solver gets no poses (a live camera without odometry); flicker still
    // finds its points from the ground-truth poses.
    stereo.next(left, right, r, f.hasPose && !args.has("blind") ? &f.pose : nullptr);

    FrameRow row;
    row.timestampNs = f.timestampNs;
    row.warm = r.warm;
    row.redone = r.redone;
    row.ms = r.totalMs;
    ImageF error;
    row.m = evaluate(in.rig, r.warp, r.depth.radial, gt.depth0, gt.depth1.empty() ? nullptr : &gt.depth1, &error);
    if (!gt.mover.empty()) row.tau1Mover = maskedTau(error, gt.mover, 1.0, &row.moverPixels);
    if (prev && prev->hasPose && f.hasPose)
      row.flicker =
          flicker(in.rig.cam0, estPrev, gtPrev, r.depth.radial, gt.depth0, moverPrev.empty() ? nullptr : &moverPrev,
                  gt.mover.empty() ? nullptr : &gt.mover, motionBetween(prev->pose, f.pose), &row.flickerPoints);
    run.frames.push_back(row);

    estPrev = r.depth.radial;
    gtPrev = std::move(gt.depth0);
    moverPrev = std::move(gt.mover);
    prev = &f;
    const double wallS = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    progressLine(run, i + 1, in.frames, wallS, i + 1 == in.frames);
  }
  return run;
}

// --- output ---

std::string num(double v, const char* fmt) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}
std::string signedNum(double v) { return num(v, "%+.2f"); }

void printRun(const Run& run) {
  std::printf("\n%s, %s: per frame (tau in %% of evaluated pixels; flicker in %% against the previous frame)\n",
              run.sequence.c_str(), run.mode.c_str());
  std::printf("%5s  %-14s %-6s %8s %8s %8s %9s %9s %8s\n", "frame", "t_ns", "state", "tau>1", "tau>3", "noc>1",
              "mover>1", "flicker", "ms");
  for (size_t i = 0; i < run.frames.size(); ++i) {
    const FrameRow& r = run.frames[i];
    std::printf("%5zu  %-14lld %-6s %8.2f %8.2f %8.2f %9s %9s %8.0f\n", i, (long long)r.timestampNs, r.state(),
                r.m.tau1, r.m.tau3, r.m.tau1Noc, num(r.tau1Mover, "%.2f").c_str(), num(100 * r.flicker, "%.3f").c_str(),
                r.ms);
  }
  const Summary s = summarize(run);
  std::printf(
      "summary %s %s: mean tau>1 %.2f %%  tau>3 %.2f %%  noc tau>1 %.2f %%  mover tau>1 %s %%  flicker %s %% "
      "(%d pairs)  frames warm/cold/redone %d/%d/%d  %.1f ms/frame\n",
      run.sequence.c_str(), run.mode.c_str(), s.tau1, s.tau3, s.tau1Noc, num(s.tau1Mover, "%.2f").c_str(),
      num(100 * s.flicker, "%.3f").c_str(), s.flickerPairs, s.warm, s.cold, s.redone, s.ms);
}

// The figures the warm start is judged by: flicker warm / cold, and the change of mean tau>1
// (all pixels and the moving object's) from cold to warm.
struct Judged {
  double flickerRatio, dTau1, dTau1Mover;
};
Judged judge(const Summary& cold, const Summary& warm) {
  return {warm.flicker / cold.flicker, warm.tau1 - cold.tau1, warm.tau1Mover - cold.tau1Mover};
}

void printCompare(const Run& cold, const Run& warm) {
  std::printf("\n%s, cold | warm per frame\n", cold.sequence.c_str());
  std::printf("%5s  %-14s %8s %9s %9s | %-6s %8s %9s %9s\n", "frame", "t_ns", "tau>1", "mover>1", "flicker", "state",
              "tau>1", "mover>1", "flicker");
  for (size_t i = 0; i < cold.frames.size() && i < warm.frames.size(); ++i) {
    const FrameRow &c = cold.frames[i], &w = warm.frames[i];
    std::printf("%5zu  %-14lld %8.2f %9s %9s | %-6s %8.2f %9s %9s\n", i, (long long)c.timestampNs, c.m.tau1,
                num(c.tau1Mover, "%.2f").c_str(), num(100 * c.flicker, "%.3f").c_str(), w.state(), w.m.tau1,
                num(w.tau1Mover, "%.2f").c_str(), num(100 * w.flicker, "%.3f").c_str());
  }
  const Summary sc = summarize(cold), sw = summarize(warm);
  const Judged j = judge(sc, sw);
  std::printf("\n%-24s %10s %10s %12s\n", cold.sequence.c_str(), "cold", "warm", "warm vs cold");
  auto line = [](const char* what, double c, double w, const std::string& cmp) {
    std::printf("%-24s %10s %10s %12s\n", what, num(c, "%.2f").c_str(), num(w, "%.2f").c_str(), cmp.c_str());
  };
  line("mean tau>1 %", sc.tau1, sw.tau1, signedNum(j.dTau1));
  line("mean tau>3 %", sc.tau3, sw.tau3, signedNum(sw.tau3 - sc.tau3));
  line("mean noc tau>1 %", sc.tau1Noc, sw.tau1Noc, signedNum(sw.tau1Noc - sc.tau1Noc));
  line("mean mover tau>1 %", sc.tau1Mover, sw.tau1Mover, signedNum(j.dTau1Mover));
  std::printf("%-24s %10s %10s %12s\n", "mean flicker %", num(100 * sc.flicker, "%.3f").c_str(),
              num(100 * sw.flicker, "%.3f").c_str(), ("x" + num(j.flickerRatio, "%.3f")).c_str());
  line("ms per frame", sc.ms, sw.ms, "x" + num(sw.ms / sc.ms, "%.2f"));
  std::printf("%-24s %10s %10s\n", "frames warm/cold/redone",
              (std::to_string(sc.warm) + "/" + std::to_string(sc.cold) + "/" + std::to_string(sc.redone)).c_str(),
              (std::to_string(sw.warm) + "/" + std::to_string(sw.cold) + "/" + std::to_string(sw.redone)).c_str());
  std::printf("judged %s: flicker warm/cold %s, delta mean tau>1 %s, delta mover tau>1 %s (warm - cold, points)\n",
              cold.sequence.c_str(), num(j.flickerRatio, "%.3f").c_str(), signedNum(j.dTau1).c_str(),
              signedNum(j.dTau1Mover).c_str());
}

// One row per frame and run, then one "mean" row per run (state: its frames warm/cold/redone;
// mover_px: frames with mover pixels; flicker_points: pairs with a flicker). tau in percent,
// flicker and absrel as fractions.
void writeCsv(const std::string& path, const std::vector<Run>& runs) {
  std::ofstream f(path);
  if (!f) throw Error("cannot write '" + path + "'");
  f << "sequence,mode,frame,t_ns,state,tau1,tau3,tau1_noc,tau3_noc,tau1_mover,mover_px,flicker,flicker_points,"
       "absrel,density,ms\n";
  auto csvNum = [](double v, const char* fmt) { return std::isfinite(v) ? num(v, fmt) : std::string(); };
  for (const Run& run : runs) {
    for (size_t i = 0; i < run.frames.size(); ++i) {
      const FrameRow& r = run.frames[i];
      f << run.sequence << ',' << run.mode << ',' << i << ',' << r.timestampNs << ',' << r.state() << ','
        << num(r.m.tau1, "%.3f") << ',' << num(r.m.tau3, "%.3f") << ',' << num(r.m.tau1Noc, "%.3f") << ','
        << num(r.m.tau3Noc, "%.3f") << ',' << csvNum(r.tau1Mover, "%.3f") << ',' << r.moverPixels << ','
        << csvNum(r.flicker, "%.6f") << ',' << r.flickerPoints << ',' << num(r.m.absRel, "%.5f") << ','
        << num(r.m.density, "%.3f") << ',' << num(r.ms, "%.1f") << '\n';
    }
    const Summary s = summarize(run);
    f << run.sequence << ',' << run.mode << ",mean,," << s.warm << '/' << s.cold << '/' << s.redone << ','
      << csvNum(s.tau1, "%.3f") << ',' << csvNum(s.tau3, "%.3f") << ',' << csvNum(s.tau1Noc, "%.3f") << ','
      << csvNum(meanOf(run.frames, [](const FrameRow& r) { return r.m.tau3Noc; }), "%.3f") << ','
      << csvNum(s.tau1Mover, "%.3f") << ',' << s.moverFrames << ',' << csvNum(s.flicker, "%.6f") << ','
      << s.flickerPairs << ',' << csvNum(s.absRel, "%.5f") << ',' << csvNum(s.density, "%.3f") << ','
      << csvNum(s.ms, "%.1f") << '\n';
  }
}

std::string markdownRuns(const std::vector<Run>& runs, const Params& params, const Args& args) {
  std::string s = "Settings: " + describe(params) + "; backend " + args.get("backend", "auto") +
                  " (cold: warm start and temporal filter off)\n\n";
  s += "### Summary\n\nMeans over frames (tau in % of evaluated pixels, a missing estimate an error; mover: the "
       "moving object's pixels; flicker in % over the pairs of consecutive frames).\n\n";
  s += "| sequence | mode | tau>1 % | tau>3 % | noc tau>1 % | mover tau>1 % | flicker % | warm/cold/redone | ms |\n";
  s += "|---|---|---|---|---|---|---|---|---|\n";
  for (const Run& run : runs) {
    const Summary m = summarize(run);
    s += "| " + run.sequence + " | " + run.mode + " | " + num(m.tau1, "%.2f") + " | " + num(m.tau3, "%.2f") + " | " +
         num(m.tau1Noc, "%.2f") + " | " + num(m.tau1Mover, "%.2f") + " | " + num(100 * m.flicker, "%.3f") + " | " +
         std::to_string(m.warm) + "/" + std::to_string(m.cold) + "/" + std::to_string(m.redone) + " | " +
         num(m.ms, "%.1f") + " |\n";
  }
  // With --compare: the judged figures per sequence.
  std::string judged;
  for (size_t i = 0; i + 1 < runs.size(); ++i)
    if (runs[i].mode == "cold" && runs[i + 1].mode == "warm" && runs[i].sequence == runs[i + 1].sequence) {
      const Judged j = judge(summarize(runs[i]), summarize(runs[i + 1]));
      judged += "| " + runs[i].sequence + " | " + num(j.flickerRatio, "%.3f") + " | " + signedNum(j.dTau1) + " | " +
                signedNum(j.dTau1Mover) + " |\n";
    }
  if (!judged.empty())
    s += "\n### Warm against cold\n\n| sequence | flicker warm/cold | delta mean tau>1 | delta mover tau>1 |\n"
         "|---|---|---|---|\n" +
         judged;
  for (const Run& run : runs) {
    s += "\n### " + run.sequence + ", " + run.mode + "\n\n";
    s += "| frame | t_ns | state | tau>1 % | tau>3 % | noc tau>1 % | mover tau>1 % | flicker % | ms |\n";
    s += "|---|---|---|---|---|---|---|---|---|\n";
    for (size_t i = 0; i < run.frames.size(); ++i) {
      const FrameRow& r = run.frames[i];
      s += "| " + std::to_string(i) + " | " + std::to_string(r.timestampNs) + " | " + r.state() + " | " +
           num(r.m.tau1, "%.2f") + " | " + num(r.m.tau3, "%.2f") + " | " + num(r.m.tau1Noc, "%.2f") + " | " +
           num(r.tau1Mover, "%.2f") + " | " + num(100 * r.flicker, "%.3f") + " | " + num(r.ms, "%.0f") + " |\n";
    }
  }
  return s;
}

// A flag given as --name (where main.cpp lists it as taking no value) or --name=on|off.
bool flag(const Args& args, const std::string& name) {
  if (!args.has(name)) return false;
  const std::string v = args.get(name, "on");
  if (v == "on" || v == "1" || v == "true" || v == "yes") return true;
  if (v == "off" || v == "0" || v == "false" || v == "no") return false;
  throw UsageError("--" + name + " takes no value, got '" + v + "' (write --" + name + "=on)");
}

}  // namespace

int runSequences(const Args& args, const Params& params, const std::string& backend) {
  for (const char* pairOnly : {"methods", "maps", "sweep", "fov", "sgbm-fov", "ps-scale", "ps-window", "ps-step",
                               "min-depth", "warps-list", "step", "plot", "replot"})
    if (args.has(pairOnly)) throw UsageError(std::string("--") + pairOnly + " is for pair folders, not --sequence");
  const bool cold = flag(args, "cold"), compare = flag(args, "compare");
  if (cold && compare) throw UsageError("--cold and --compare exclude each other (--compare runs cold, then warm)");
  const int maxFrames = args.getInt("frames", 0);
  if (maxFrames < 0) throw Error("--frames expects a count >= 1 (0: every frame)");
  std::vector<std::string> dirs{args.get("sequence", "")};
  for (const std::string& d : args.positional()) dirs.push_back(d);
  std::vector<std::string> modes;
  if (compare)
    modes = {"cold", "warm"};
  else
    modes = {cold ? "cold" : "warm"};

  // Every folder is opened and its ground truth listed before the first (long) solve.
  std::vector<SequenceInput> inputs;
  for (const std::string& dir : dirs) {
    if (dir.empty()) throw Error("--sequence needs a folder");
    inputs.push_back(openSequence(dir, args, maxFrames));
    const SequenceInput& in = inputs.back();
    std::fprintf(stderr, "%s: %s; evaluating %zu\n", in.name.c_str(), in.seq.summary().c_str(), in.frames);
    for (const std::string& w : in.seq.warnings()) std::fprintf(stderr, "%s: note: %s\n", in.name.c_str(), w.c_str());
    if (!in.depth1.present())
      std::fprintf(stderr, "%s: note: no mav0/depth1: non-occluded pixels checked for visibility only\n",
                   in.name.c_str());
    if (!in.mover0.present())
      std::fprintf(stderr, "%s: note: no mav0/mover0: no moving-object figures\n", in.name.c_str());
    size_t posed = 0;
    for (size_t i = 0; i < in.frames; ++i) posed += in.seq.frames()[i].hasPose;
    if (posed < in.frames)
      std::fprintf(stderr, "%s: note: %zu of %zu frames without a pose: no flicker next to them\n", in.name.c_str(),
                   in.frames - posed, in.frames);
  }

  std::vector<Run> runs;
  for (const SequenceInput& in : inputs) {
    for (const std::string& mode : modes) {
      runs.push_back(runSequence(in, params, backend, mode, args));
      printRun(runs.back());
    }
    if (compare) printCompare(runs[runs.size() - 2], runs.back());
    std::fflush(stdout);
    // Rewritten after each sequence so that a long run leaves partial results.
    if (args.has("csv")) writeCsv(args.get("csv", ""), runs);
    if (args.has("md")) {
      std::ofstream md(args.get("md", ""));
      if (!md) throw Error("cannot write '" + args.get("md", "") + "'");
      md << markdownRuns(runs, params, args);
    }
  }
  if (args.has("csv")) std::printf("wrote %s\n", args.get("csv", "").c_str());
  if (args.has("md")) std::printf("wrote %s\n", args.get("md", "").c_str());
  return 0;
}

}  // namespace cs::cli::eval

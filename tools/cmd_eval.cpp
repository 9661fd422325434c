// curvestereo eval PAIRDIR... --csv FILE [--md FILE] [--maps DIR] [--methods LIST]
//   accuracy of our method and of the paper's baselines on pairs with ground truth
//   (docs/accuracy.md "How accuracy is measured"), or, with --sweep, the paper's two parameter
//   studies (eval_study.cpp). Tables: eval_report.cpp; pictures: eval_sheet.cpp.
// curvestereo eval --sequence DIR [DIR...] [--cold | --compare] [--frames N] [--calib FILE]
//                  [--csv FILE] [--md FILE]
//   a sequence with ground truth frame after frame: per-frame tau, the moving object's tau
//   and the flicker (eval_sequence.cpp). --cold / --compare take no value where main.cpp
//   lists them as flags; --cold=on / --compare=on work either way.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "baselines/methods.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/metrics.hpp"
#include "eval.hpp"
#include "rig_cli.hpp"

namespace cs::cli {

namespace eval {

namespace fs = std::filesystem;

Pair loadPair(const std::string& dir) {
  auto in = [&](const char* name) { return (fs::path(dir) / name).string(); };
  Pair p;
  p.dir = dir;
  const fs::path norm = fs::path(dir).lexically_normal();
  p.name = norm.filename().string().empty() ? norm.parent_path().filename().string() : norm.filename().string();
  p.rig = loadKalibr(in("camchain.yaml"));
  p.left = loadImageFor(in("left.png"), p.rig.cam0, "left");
  p.right = loadImageFor(in("right.png"), p.rig.cam1, "right");
  p.depthLeft = readExr(in("depth_left.exr"));
  if (p.depthLeft.width != p.left.width || p.depthLeft.height != p.left.height)
    throw Error("'" + in("depth_left.exr") + "' does not match the image size");
  if (fs::exists(in("depth_right.exr"))) p.depthRight = readExr(in("depth_right.exr"));
  return p;
}

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}
std::vector<double> numberList(const std::string& s, const char* option) {
  std::vector<double> out;
  for (const std::string& item : splitList(s)) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (!end || *end || !std::isfinite(v))
      throw Error(std::string("option --") + option + " expects numbers, got '" + item + "'");
    out.push_back(v);
  }
  if (out.empty()) throw Error(std::string("option --") + option + " is empty");
  return out;
}
std::string fovName(double fov) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", fov);
  return buf;
}

double tauPercent(const ImageF& error, double k, Missing missing) {
  long long n = 0, bad = 0;
  for (float e : error.data) {
    if (std::isnan(e) || (missing == Missing::Skipped && std::isinf(e))) continue;
    ++n;
    bad += e > k;
  }
  return n ? 100.0 * double(bad) / double(n) : 0.0;
}

}  // namespace eval

namespace {

using namespace eval;
using baselines::MethodResult;

// The methods of one run, in table order.
struct Plan {
  std::vector<std::string> methods;  // ours, rectified-tgv-F, planesweep, planesweep-valid, opencv-sgbm-F
};

Plan makePlan(const Args& args) {
  const std::vector<double> fovs = numberList(args.get("fov", "90,165"), "fov");
  const std::vector<double> sgbmFovs = numberList(args.get("sgbm-fov", "120"), "sgbm-fov");
  std::vector<std::string> want = splitList(args.get("methods", "ours"));
  Plan plan;
  auto add = [&](const std::string& m) {
    if (std::find(plan.methods.begin(), plan.methods.end(), m) == plan.methods.end()) plan.methods.push_back(m);
  };
  for (const std::string& m : want) {
    if (m == "all" || m == "ours") add("ours");
    if (m == "all" || m == "rectified-tgv")
      for (double f : fovs) add("rectified-tgv-" + fovName(f));
    if (m == "all" || m == "planesweep") add("planesweep");
    if (m == "all" || m == "planesweep-valid") add("planesweep-valid");
    if (m == "all" || m == "opencv-sgbm") {
      if (baselines::sgbmAvailable()) {
        for (double f : sgbmFovs) add("opencv-sgbm-" + fovName(f));
      } else {
        std::fprintf(stderr,
                     "eval: opencv-sgbm is unavailable (built without OpenCV: install libopencv-dev and re-run cmake); "
                     "skipped\n");
      }
    }
    const bool known = m == "all" || m == "ours" || m == "rectified-tgv" || m == "planesweep" ||
                       m == "planesweep-valid" || m == "opencv-sgbm";
    if (!known) {
      if (m.rfind("rectified-tgv-", 0) == 0) {
        numberList(m.substr(14), "methods");
        add(m);
      } else if (m.rfind("opencv-sgbm-", 0) == 0) {
        numberList(m.substr(12), "methods");
        if (!baselines::sgbmAvailable())
          throw Error("method " + m +
                      " is unavailable: curvestereo was built without OpenCV (install libopencv-dev and re-run cmake)");
        add(m);
      } else {
        throw Error("unknown method '" + m +
                    "' (known: ours, rectified-tgv[-FOV], planesweep, planesweep-valid, opencv-sgbm[-FOV], all)");
      }
    }
  }
  if (plan.methods.empty()) throw Error("no method to evaluate");
  return plan;
}

baselines::PlaneSweepOptions sweepOptions(const Args& args) {
  baselines::PlaneSweepOptions o;
  o.sweep.scale = args.getDouble("ps-scale", o.sweep.scale);
  o.sweep.window = args.getInt("ps-window", o.sweep.window);
  o.sweep.pxPerPlane = args.getDouble("ps-step", o.sweep.pxPerPlane);
  o.sweep.minDepth = args.getDouble("min-depth", o.sweep.minDepth);
  return o;
}

// Runs every planned method on one pair; returns the rows and (for the sheet) results, and
// ours's sparsification when `curve` is given.
std::vector<Row> evaluatePair(const Pair& p, const Plan& plan, const Args& args, const Params& params,
                              const std::string& backend, const std::string& maps, Sparsification* curve) {
  std::map<std::string, MethodResult> results;
  ImageF confidence;
  MethodResult psAll, psValid;
  bool psDone = false;
  for (const std::string& m : plan.methods) {
    std::fprintf(stderr, "%s: %s ...\n", p.name.c_str(), m.c_str());
    if (m == "ours") {
      Stereo stereo(p.rig, params, backend);
      Progress progress(p.name);
      stereo.setProgress([&](double f) { progress(f); });
      DepthResult r = stereo.compute(p.left, p.right);
      progress.done();
      results[m] = MethodResult{r.warp, r.depth.radial, r.totalMs};
      confidence = std::move(r.confidence);
    } else if (m.rfind("rectified-tgv-", 0) == 0) {
      const double fov = std::stod(m.substr(14));
      results[m] = baselines::runRectifiedTgv(p.rig, p.left, p.right, params, backend, fov, p.left.width);
    } else if (m == "planesweep" || m == "planesweep-valid") {
      if (!psDone) baselines::runPlaneSweep(p.rig, p.left, p.right, sweepOptions(args), psAll, psValid);
      psDone = true;
      results[m] = m == "planesweep" ? psAll : psValid;
    } else if (m.rfind("opencv-sgbm-", 0) == 0) {
      const double fov = std::stod(m.substr(12));
      results[m] = baselines::runSgbm(p.rig, p.left, p.right, baselines::SgbmOptions{}, fov, p.left.width);
    }
  }

  std::vector<Row> rows;
  std::map<std::string, ImageF> errors;
  const ImageF* dr = p.depthRight.empty() ? nullptr : &p.depthRight;
  for (const std::string& m : plan.methods) {
    const MethodResult& r = results[m];
    ImageF error;
    rows.push_back({p.name, m, evaluate(p.rig, r.warp, r.depth, p.depthLeft, dr, &error), r.ms});
    rows.back().tau1Est = tauPercent(error, 1.0, Missing::Skipped);
    rows.back().tau3Est = tauPercent(error, 3.0, Missing::Skipped);
    if (m == "ours" && curve) *curve = sparsification(error, confidence, 1.0);
    errors[m] = std::move(error);
  }

  if (!maps.empty()) {
    std::vector<SheetEntry> entries;
    for (size_t i = 0; i < plan.methods.size(); ++i) {
      const std::string& m = plan.methods[i];
      entries.push_back({m, &results[m].depth, &errors[m], rows[i].m.tau1, rows[i].m.tau3});
    }
    writeSheet(maps, p, entries);
  }
  return rows;
}

}  // namespace

int cmdEval(const Args& args) {
  std::set<std::string> known = kSolverOptions;
  known.insert({"csv", "md", "maps", "methods", "fov", "sgbm-fov", "ps-scale", "ps-window", "ps-step", "min-depth",
                "sweep", "warps-list", "step", "plot", "replot", "sparsification"});
  known.insert({"sequence", "cold", "compare", "frames", "calib", "blind"});
  known.insert(kRigOptions.begin(), kRigOptions.end());
  args.allowOnly(known);
  if (args.has("sequence")) return runSequences(args, paramsFromArgs(args), backendFromArgs(args));
  for (const char* sequenceOnly : {"cold", "compare", "frames", "calib"})
    if (args.has(sequenceOnly)) throw UsageError(std::string("--") + sequenceOnly + " is for --sequence folders");
  if (args.positional().empty()) throw UsageError("eval needs at least one pair folder (or --sequence DIR)");
  if (isRigFolder(args.positional().front())) {
    for (const char* pairOnly : {"md", "methods", "sweep", "sparsification"})
      if (args.has(pairOnly)) throw UsageError(std::string("--") + pairOnly + " is for pair folders, not a rig folder");
    return evalRig(args);
  }
  for (const char* rigOnly : kRigOptions)
    if (args.has(rigOnly)) throw UsageError(std::string("--") + rigOnly + " is for a rig folder");
  const Params params = paramsFromArgs(args);
  const std::string backend = backendFromArgs(args);
  if (args.has("sweep")) return runStudy(args, params, backend);
  const std::string csv = args.require("csv");
  const Plan plan = makePlan(args);
  std::vector<Row> rows;
  const std::string curvesPath = args.get("sparsification", "");
  if (args.has("sparsification") && std::find(plan.methods.begin(), plan.methods.end(), "ours") == plan.methods.end())
    throw Error("--sparsification ranks ours's pixels by its confidence: add ours to --methods");
  std::vector<std::pair<std::string, Sparsification>> curves;
  for (const std::string& dir : args.positional()) {
    const Pair pair = loadPair(dir);
    Sparsification curve;
    const std::vector<Row> pairRows =
        evaluatePair(pair, plan, args, params, backend, args.get("maps", ""), curvesPath.empty() ? nullptr : &curve);
    if (!curvesPath.empty()) {
      printSparsification(pair.name, curve);
      curves.push_back({pair.name, curve});
      writeSparsification(curvesPath, curves);
    }
    for (const Row& r : pairRows) {
      rows.push_back(r);
      std::printf(
          "%-22s %-18s tau>1 %6.2f %%  tau>3 %6.2f %%  EPE %7.3f px  abs-rel %5.2f %%  density %5.1f %%  %6.0f ms\n",
          r.pair.c_str(), r.method.c_str(), r.m.tau1, r.m.tau3, r.m.epe, 100 * r.m.absRel, r.m.density, r.ms);
      if (r.m.skyPixels > 0)
        std::printf("%-22s %-18s sky: %.1f %% of %lld sky pixels at +inf or invalid\n", r.pair.c_str(),
                    r.method.c_str(), r.m.sky, r.m.skyPixels);
    }
    std::fflush(stdout);
    writeCsv(csv, rows);  // rewritten after each pair so a long run leaves partial results
    if (args.has("md")) {
      std::ofstream md(args.get("md", ""));
      if (!md) throw Error("cannot write '" + args.get("md", "") + "'");
      md << markdown(rows, params, args);
    }
  }
  std::printf("wrote %s\n", csv.c_str());
  return 0;
}

}  // namespace cs::cli

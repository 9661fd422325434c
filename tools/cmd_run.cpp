// curvestereo run --calib CAMCHAIN LEFT RIGHT -o OUTDIR [--backend B] [--preset P] [--mask PNG]
#include <cstdio>

#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/image_io.hpp"

namespace cs::cli {

namespace {

// A lens mask PNG (non-zero = use the pixel), e.g. the T265's image circle.
ImageU8 loadMask(const std::string& path) {
  ImageF m = readPngGray(path);
  ImageU8 out(m.width, m.height);
  for (size_t i = 0; i < m.size(); ++i) out.data[i] = m.data[i] > 0.5f;
  return out;
}

}  // namespace

int cmdRun(const Args& args) {
  std::set<std::string> known = kSolverOptions;
  known.insert({"min-confidence", "calib", "o", "output", "scale-intrinsics"});
  args.allowOnly(known);
  if (args.positional().size() != 2) throw Error("run needs exactly two images: LEFT RIGHT");
  const std::string outDir = args.has("o") ? args.get("o", "") : args.require("output");
  const Params params = paramsFromArgs(args);
  const float minConfidence = minConfidenceFromArgs(args, params);
  const StereoInputs in =
      loadStereoInputs(args.require("calib"), args.positional()[0], args.positional()[1], args.has("scale-intrinsics"));
  const Rig& rig = in.rig;
  const ImageF& left = in.left;
  const ImageF& right = in.right;

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

  long long valid = 0;
  for (auto v : r.valid.data) valid += v;
  std::printf("stages: %s\n", formatStages(r.stages).c_str());
  std::printf("total %.1f ms, %lld valid pixels (%.1f %% of the image); outputs in %s\n", r.totalMs, valid,
              100.0 * double(valid) / double(r.valid.size()), outDir.c_str());
  return 0;
}

}  // namespace cs::cli

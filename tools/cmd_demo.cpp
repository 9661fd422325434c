// curvestereo demo: no inputs needed. Renders a synthetic fisheye pair with exact ground
// truth, solves it, writes the outputs and reports accuracy and time. With --camera t265
// (and the camera-model overrides of synth) the pair is first passed through a model of
// a real low-cost fisheye camera, so the demo shows the method on images like a T265's.
#include <cstdio>
#include <filesystem>

#include "camera_options.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/metrics.hpp"
#include "synth/scene.hpp"

namespace cs::cli {

int cmdDemo(const Args& args) {
  std::set<std::string> known = kSolverOptions;
  known.insert(kCameraOptions.begin(), kCameraOptions.end());
  known.insert({"min-confidence", "o", "output", "size", "seed", "scene"});
  args.allowOnly(known);
  const std::string outDir = args.get("o", args.get("output", "demo_out"));
  synth::SynthConfig cfg;
  cfg.camera = synth::defaultFisheye(args.getInt("size", 480));
  cfg.scene = args.get("scene", "urban");
  cfg.seed = uint32_t(args.getInt("seed", 7));
  cfg.baseline = 0.12;
  cfg.nearest = 1.5;
  cfg.samplesPerAxis = 3;
  const synth::CameraPhotometry camera = cameraModelFromArgs(args, cfg.seed);

  std::printf("rendering a %dx%d %s scene, binocular fisheye rig, %.0f cm baseline\n", cfg.camera.width,
              cfg.camera.height, cfg.scene.c_str(), 100 * cfg.baseline);
  Progress renderProgress("rendering");
  synth::SynthPair pair = synth::renderPair(cfg, [&](double f) { renderProgress(f); });
  renderProgress.done();
  std::filesystem::create_directories(outDir);
  auto path = [&](const char* name) { return (std::filesystem::path(outDir) / name).string(); };
  if (camera.enabled()) {
    const double exposureScale = synth::applyPhotometry(camera, pair);
    std::printf("camera model %s\n", synth::describePhotometry(camera, exposureScale).c_str());
    writePhotometryJson(camera, exposureScale, outDir);
  }
  writePairImage(path("left.png"), pair.left, camera);
  writePairImage(path("right.png"), pair.right, camera);
  writeExr(path("depth_left.exr"), pair.depthLeft);
  writeDepthPng(path("depth_gt.png"), pair.depthLeft);
  saveKalibr(pair.rig, path("camchain.yaml"));

  const Params params = paramsFromArgs(args);
  const float minConfidence = minConfidenceFromArgs(args);
  Stereo stereo(pair.rig, params, backendFromArgs(args));
  std::printf("backend: %s - %s\nsettings: %s\n", stereo.deviceName().c_str(), stereo.backendChoice().c_str(),
              describe(params).c_str());
  stereo.setProfiling(true);  // one frame: the stage breakdown is worth a synchronisation
  Progress progress("solving");
  stereo.setProgress([&](double f) { progress(f); });
  DepthResult r = stereo.compute(pair.left, pair.right);
  progress.done();
  writeOutputs(outDir, r, pair.left, minConfidence);

  const Metrics m = evaluate(pair.rig, r.warp, r.depth.radial, pair.depthLeft, &pair.depthRight);
  std::printf("stages: %s\n", formatStages(r.stages).c_str());
  std::printf("tau>1 %.2f %%  tau>3 %.2f %%  EPE %.3f px  depth abs-rel %.2f %%  (%lld pixels with ground truth)\n",
              m.tau1, m.tau3, m.epe, 100 * m.absRel, m.evaluated);
  std::printf("time %.0f ms per frame; outputs in %s/ (depth.png: colour-coded depth; depth_gt.png: truth)\n",
              r.totalMs, outDir.c_str());
  return 0;
}

}  // namespace cs::cli

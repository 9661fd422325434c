// curvestereo fields --calib CAMCHAIN -o OUTDIR: the per-rig fields as .flo and pictures.
#include <cstdio>
#include <filesystem>

#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/fields.hpp"
#include "curvestereo/image_io.hpp"

namespace cs::cli {

namespace {

FlowImage maskedFlow(const FlowImage& f, const ImageU8& mask) {
  FlowImage out = f;
  for (size_t i = 0; i < out.size(); ++i)
    if (!mask.data[i]) out.data[i] = {kFloUnknown, kFloUnknown};
  return out;
}

float maxMagnitude(const FlowImage& f, const ImageU8& mask) {
  float m = 1e-6f;
  for (size_t i = 0; i < f.size(); ++i)
    if (mask.data[i]) m = std::max(m, std::hypot(f.data[i].x, f.data[i].y));
  return m;
}

}  // namespace

int cmdFields(const Args& args) {
  args.allowOnly({"calib", "o", "output", "max-fov", "epipole", "image-size"});
  const std::string outDir = args.has("o") ? args.get("o", "") : args.require("output");
  const Rig rig = loadCalibration(args.require("calib"), nullptr, calibHintsFromArgs(args));
  FieldOptions opt;
  // The solver's defaults, so that the mask shown is the one it solves on.
  opt.maxFovDeg = args.getDouble("max-fov", Params{}.maxFovDeg);
  opt.epipoleDeg = args.getDouble("epipole", Params{}.epipoleDeg);
  const RigFields f = computeFields(rig.cam0, rig.cam1, rig.R, rig.t, opt);

  std::filesystem::create_directories(outDir);
  auto path = [&](const char* name) { return (std::filesystem::path(outDir) / name).string(); };
  ImageF maskImage(f.mask.width, f.mask.height);
  for (size_t i = 0; i < f.mask.size(); ++i) maskImage.data[i] = f.mask.data[i];
  writePngGray(path("mask.png"), maskImage);
  const FlowImage calib = maskedFlow(f.calibration, f.mask), traj = maskedFlow(f.trajectory, f.mask);
  writeFlo(path("calibration.flo"), calib);
  writeFlo(path("trajectory.flo"), traj);
  const float calibMax = maxMagnitude(f.calibration, f.mask);
  writePngRgb(path("calibration.png"), colorizeFlow(calib, calibMax));
  writePngRgb(path("trajectory.png"), colorizeFlow(traj, 1.f));

  long long valid = 0;
  for (auto v : f.mask.data) valid += v;
  std::printf("%dx%d, %lld valid pixels (%.1f %%), largest calibration offset %.2f px; written to %s\n", f.mask.width,
              f.mask.height, valid, 100.0 * double(valid) / double(f.mask.size()), calibMax, outDir.c_str());
  return 0;
}

}  // namespace cs::cli

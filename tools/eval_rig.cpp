// curvestereo eval RIGDIR [--csv FILE] [--maps DIR] [--pairs I-J,... | --partners N]
//                         [--cross-check T] [--panorama-min-confidence C] [--whole-images] [--one-way]
//                         [solver options]
// A rig folder (../shared/data/rigs layout): each camera's tau against its depth<k>.exr, in
// the pixel terms of its pairs; the panorama's range error where the truth is finite, as a
// relative error and as tau in the panorama's pixel terms (parallaxErrorPx); and the
// coverage, the share of the sphere seen by two cameras or more that gets a range.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "common.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/metrics.hpp"
#include "curvestereo/rig_fusion.hpp"
#include "curvestereo/rig_stereo.hpp"
#include "rig_cli.hpp"

namespace cs::cli {

namespace {

namespace fs = std::filesystem;

std::string camFile(const std::string& dir, const char* stem, int k, const char* ext) {
  return (fs::path(dir) / (stem + std::to_string(k) + ext)).string();
}

struct RigFolder {
  CameraRig rig;
  std::vector<ImageF> images, depths;
  ImageF panoramaRange;
};

RigFolder loadRigFolder(const std::string& dir) {
  RigFolder f;
  f.rig = loadCameraRig((fs::path(dir) / "camchain.yaml").string());
  for (int k = 0; k < f.rig.size(); ++k) {
    const Camera& cam = f.rig.cameras[size_t(k)];
    f.images.push_back(loadImageFor(camFile(dir, "cam", k, ".png"), cam, ("cam" + std::to_string(k)).c_str()));
    f.depths.push_back(readExr(camFile(dir, "depth", k, ".exr")));
    if (f.depths.back().width != cam.width || f.depths.back().height != cam.height)
      throw Error(camFile(dir, "depth", k, ".exr") + ": not the size of cam" + std::to_string(k));
  }
  f.panoramaRange = readExr((fs::path(dir) / "panorama_range.exr").string());
  if (f.panoramaRange.width != 2 * f.panoramaRange.height)
    throw Error(dir + "/panorama_range.exr: an equirectangular panorama is twice as wide as high");
  return f;
}

// A depth's warp in a pair's terms; +inf becomes a far finite depth, so that an estimate at
// infinity is scored by how far the true point's warp is from zero parallax.
FlowImage warpOf(const Rig& pair, const ImageF& depth) {
  ImageF finite = depth;
  for (float& d : finite.data)
    if (std::isinf(d) && d > 0) d = 1e9f;
  return groundTruthWarp(pair, finite);
}

struct CameraScore {
  double tau1 = 0, tau3 = 0, density = 0;
  long long pixels = 0;
};

// Each pixel that a partner sees (non-occluded, by the ground truth) is scored in the first
// such partner's pixel terms; a pixel without an estimate counts as an error.
CameraScore scoreCamera(const RigFolder& f, int k, const std::vector<int>& partners, const DepthResult& r) {
  const ImageF& gt = f.depths[size_t(k)];
  ImageF error(gt.width, gt.height, NAN);
  for (int j : partners) {
    const Rig pair = pairRig(f.rig, k, j);
    ImageF pairError;
    evaluate(pair, warpOf(pair, r.depth.radial), r.depth.radial, gt, &f.depths[size_t(j)], &pairError);
    const ImageU8 seen = nonOccludedMask(pair, gt, &f.depths[size_t(j)]);
    for (size_t p = 0; p < error.size(); ++p)
      if (std::isnan(error.data[p]) && seen.data[p] && !std::isnan(pairError.data[p]))
        error.data[p] = pairError.data[p];
  }
  CameraScore s;
  long long over1 = 0, over3 = 0, estimated = 0;
  for (float e : error.data) {
    if (std::isnan(e)) continue;
    ++s.pixels;
    over1 += e > 1.f, over3 += e > 3.f, estimated += std::isfinite(e);
  }
  auto pct = [&](long long n) { return s.pixels ? 100.0 * double(n) / double(s.pixels) : 0.0; };
  s.tau1 = pct(over1), s.tau3 = pct(over3), s.density = pct(estimated);
  return s;
}

struct PanoramaScore {
  double absRel = 0, coverage = 0, density = 0;
  double tau1 = 0, tau3 = 0;  // over `finiteSeen`: finite truth that two cameras see
  long long finite = 0, twoCameras = 0, finiteSeen = 0;
};

// tau in the panorama's own pixel terms. A range error is an error of the parallax b / rho
// that a point shows between two centres a baseline b apart (b the mean baseline of the
// solved pairs; the angle at its largest, across the baseline), counted in the panorama's
// pixels (width / 2 pi of them a radian), as a pair's tau counts its pixels of displacement.
// +inf is no parallax; a missing range is an error, as in a pair's tau.
double parallaxErrorPx(double baseline, int width, float truth, float estimate) {
  if (std::isnan(estimate)) return HUGE_VAL;
  const double pxPerRadian = double(width) / (2.0 * M_PI);
  const double estimated = std::isfinite(estimate) && estimate > 0 ? baseline / double(estimate) : 0.0;
  return std::abs(estimated - baseline / double(truth)) * pxPerRadian;
}

// The truth's pixel (i, j) looks along the panorama ray of the same pixel: run's panorama
// frame is the folders' body frame (levelled cameras, camera 0 forward, origin the centre).
// Sampled every other pixel: the sphere's shares need no more, and each sample projects into
// every camera.
PanoramaScore scorePanorama(const CameraRig& rig, const PanoramaFrame& frame, const ImageF& truth,
                            const ImageF& estimate, double baseline, ImageF* errorMap) {
  const RigViews views(rig);
  PanoramaScore s;
  double absRelSum = 0;
  long long samples = 0, withRange = 0, covered = 0, finiteEstimated = 0, over1 = 0, over3 = 0;
  for (int i = 0; i < truth.height; i += 2)
    for (int j = 0; j < truth.width; j += 2) {
      const float gt = truth(j, i), est = estimate(j, i);
      const bool estimated = !std::isnan(est), far = !std::isfinite(gt);
      ++samples, withRange += estimated;
      const Eigen::Vector3d ray = frame.R * panoramaRay(j, i, truth.width);
      const int seeing = far ? views.seeingDirection(ray) : views.seeing(frame.centre + double(gt) * ray);
      if (seeing >= 2) ++s.twoCameras, covered += estimated;
      if (far || !(gt > 0)) continue;
      ++s.finite;
      if (seeing >= 2) {
        const double e = parallaxErrorPx(baseline, truth.width, gt, est);
        ++s.finiteSeen, over1 += e > 1.0, over3 += e > 3.0;
      }
      if (!estimated) continue;
      ++finiteEstimated;  // as evaluate()'s abs-rel: over the estimates, +inf counting 1
      const double error = std::isfinite(est) ? std::min(1.0, std::abs(double(est) - gt) / gt) : 1.0;
      absRelSum += error;
      if (errorMap) (*errorMap)(j, i) = float(error);
    }
  s.density = samples ? 100.0 * double(withRange) / double(samples) : 0.0;
  s.coverage = s.twoCameras ? 100.0 * double(covered) / double(s.twoCameras) : 0.0;
  s.absRel = finiteEstimated ? 100.0 * absRelSum / double(finiteEstimated) : 0.0;
  s.tau1 = s.finiteSeen ? 100.0 * double(over1) / double(s.finiteSeen) : 0.0;
  s.tau3 = s.finiteSeen ? 100.0 * double(over3) / double(s.finiteSeen) : 0.0;
  return s;
}

// The panorama as run writes it, and its relative range error (red: 20 % or more; black:
// not evaluated), sampled as scorePanorama samples.
void writeRigMaps(const std::string& dir, const Panorama& panorama, const ImageF& errorMap) {
  fs::create_directories(dir);
  writeDepthPng((fs::path(dir) / "panorama_depth.png").string(), panorama.range);
  writePngRgb((fs::path(dir) / "panorama_error.png").string(), colorizeScalar(errorMap, 0.f, 0.2f));
}

std::vector<int> partnersOf(int k, const std::vector<PairInfo>& pairs) {
  std::vector<int> out;
  for (const PairInfo& p : pairs) {
    if (p.i == k) out.push_back(p.j);
    if (p.j == k) out.push_back(p.i);
  }
  return out;
}

}  // namespace

bool isRigFolder(const std::string& dir) {
  return fs::exists(fs::path(dir) / "cam0.png") && fs::exists(fs::path(dir) / "panorama_range.exr");
}

int evalRig(const Args& args) {
  if (args.positional().size() != 1) throw UsageError("eval takes one rig folder at a time");
  const std::string dir = args.positional()[0];
  const RigFolder f = loadRigFolder(dir);
  const std::vector<PairInfo> pairs = rigPairsFromArgs(args, f.rig);
  const Params params = rigParamsFromArgs(args, f.rig);
  const float panoramaConfidence = panoramaMinConfidence(args);
  const std::unique_ptr<RigStereo> solver = rigStereoFromArgs(args, f.rig, pairs, params);
  RigStereo& stereo = *solver;
  std::printf("rig %s: %d cameras; backend %s; pairs %s\n", dir.c_str(), f.rig.size(), stereo.backendName().c_str(),
              describePairs(pairs).c_str());
  const PanoramaFrame frame = panoramaFrame(f.rig);
  stereo.setPanorama(f.panoramaRange.width, frame, panoramaConfidence);
  const RigResult r = stereo.compute(f.images);
  const Panorama& panorama = r.panorama;

  std::string csv = "camera,tau1,tau3,density,pixels\n";
  for (int k = 0; k < f.rig.size(); ++k) {
    const CameraScore s = scoreCamera(f, k, partnersOf(k, pairs), r.cameras[size_t(k)]);
    std::printf("cam%d  tau>1 %6.2f %%  tau>3 %6.2f %%  density %5.1f %%  (%lld px seen by a partner)\n", k, s.tau1,
                s.tau3, s.density, s.pixels);
    csv += "cam" + std::to_string(k) + "," + std::to_string(s.tau1) + "," + std::to_string(s.tau3) + "," +
           std::to_string(s.density) + "," + std::to_string(s.pixels) + "\n";
  }
  ImageF errorMap(panorama.range.width, panorama.range.height, NAN);
  double baseline = 0;
  for (const PairInfo& pair : pairs) baseline += pair.baseline / double(pairs.size());
  const PanoramaScore p = scorePanorama(f.rig, frame, f.panoramaRange, panorama.range, baseline, &errorMap);
  if (args.has("maps")) writeRigMaps(args.get("maps", ""), panorama, errorMap);
  std::printf(
      "panorama %dx%d  abs-rel %5.2f %% (finite truth)  coverage %5.1f %% (of the sphere two cameras see)  "
      "density %5.1f %%\n",
      panorama.range.width, panorama.range.height, p.absRel, p.coverage, p.density);
  std::printf(
      "panorama tau>1 %5.2f %%  tau>3 %5.2f %% (parallax over a %.3f m baseline, in panorama pixels; finite "
      "truth two cameras see)\n",
      p.tau1, p.tau3, baseline);
  std::printf("time: %.1f ms: %zu solves, the panorama (%s; %.1f ms after the solves) and the per-camera fusion\n",
              r.totalMs, r.solves.size(), stereo.backendName().c_str(), r.panoramaMs);
  if (args.has("csv")) {
    csv += "panorama_tau1," + std::to_string(p.tau1) + "\npanorama_tau3," + std::to_string(p.tau3) + "\n";
    csv += "panorama_absrel," + std::to_string(p.absRel) + "\npanorama_coverage," + std::to_string(p.coverage) +
           "\npanorama_density," + std::to_string(p.density) + "\nms," + std::to_string(r.totalMs) + "\n";
    std::ofstream out(args.get("csv", ""));
    if (!(out << csv)) throw Error(args.get("csv", "") + ": cannot write");
  }
  return 0;
}

}  // namespace cs::cli

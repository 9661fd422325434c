// RigStereo (rig_stereo.hpp): a rig's pairs through Stereo, then the per-camera fusion.
#include "curvestereo/rig_stereo.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <thread>

#include "curvestereo/stereo.hpp"

namespace cs {

namespace {

constexpr const char* kOneWayCrossCheck =
    "the cross-check compares a pair's two directions: one way (--one-way) solves only one";

}  // namespace

Params rigParams(const CameraRig& rig, Params params) {
  double widest = 0;
  for (const Camera& cam : rig.cameras) widest = std::max(widest, viewHalfAngle(cam));
  // Rounded down to a micro-degree: never wider than the widest lens.
  params.maxFovDeg = std::max(params.maxFovDeg, std::floor(2.0 * widest * 180.0 / M_PI * 1e6) / 1e6);
  return params;
}

RigStereo::RigStereo(const CameraRig& rig, const std::vector<PairInfo>& pairs, const Params& params,
                     const std::string& backend, bool solveWindows)
    : rig_(rig), pairs_(pairs), params_(params), backend_(backend), windows_(solveWindows) {
  rig_.validate();
  buildDirections();
  std::vector<bool> covered(size_t(rig.size()), false);
  for (const PairInfo& p : pairs_) covered[size_t(p.i)] = covered[size_t(p.j)] = true;
  for (int k = 0; k < rig.size(); ++k)
    if (!covered[size_t(k)]) throw Error("cam" + std::to_string(k) + " is in none of the pairs to solve");
  for (const Camera& cam : rig_.cameras) rays_.push_back(cameraRays(cam));
}

void RigStereo::buildDirections() {
  directions_.clear();
  const FieldOptions fields{params_.maxFovDeg, params_.epipoleDeg};
  std::vector<int> solvesFrom(size_t(rig_.size()), 0);
  for (const PairInfo& p : pairs_) {
    // One way: from the camera that solves fewer so far (ties: the first of the pair).
    const int from = solvesFrom[size_t(p.j)] < solvesFrom[size_t(p.i)] ? p.j : p.i;
    for (const auto& [a, b] : {std::pair{p.i, p.j}, std::pair{p.j, p.i}}) {
      if (oneWay_ && a != from) continue;
      ++solvesFrom[size_t(a)];
      Rig pair = pairRig(rig_, a, b);
      ImageWindow window{0, 0, pair.cam0.width, pair.cam0.height};
      if (windows_) {
        window = solvableWindow(pair, fields, kWindowMargin);
        if (window.empty())
          throw Error("cam" + std::to_string(a) + " sees nothing of cam" + std::to_string(b) +
                      "'s view within the field of view (max_fov_deg " + std::to_string(params_.maxFovDeg) + ")");
        pair.cam0 = pair.cam0.cropped(window.x0, window.y0, window.width, window.height);
      }
      directions_.push_back({a, b, window, std::make_unique<Stereo>(pair, params_, backend_), ImageF()});
    }
  }
  estimates_.assign(directions_.size(), DepthResult());
  applyOutputs();
  if (panorama_) setPanorama(panoramaWidth_, panoramaFrame_, panoramaMinConfidence_);  // new views
}

void RigStereo::setOneWay(bool on) {
  if (on == oneWay_) return;
  if (on && crossCheck_ > 0) throw Error(kOneWayCrossCheck);
  oneWay_ = on;
  buildDirections();
}

void RigStereo::setCameraOutputs(bool on) { cameraOutputs_ = on; }

void RigStereo::setPanorama(int width, const PanoramaFrame& frame, float minConfidence) {
  if (!(minConfidence >= 0.f && minConfidence <= 1.f)) throw Error("panorama min confidence must be in [0, 1]");
  panorama_.reset();
  panoramaWidth_ = width;
  panoramaFrame_ = frame;
  panoramaMinConfidence_ = minConfidence;
  if (width > 0) panorama_ = std::make_unique<PanoramaFusion>(rig_, frame, width, views(), rays_, backendName());
}

std::vector<PanoramaView> RigStereo::views() const {
  std::vector<PanoramaView> out;
  for (const Direction& dir : directions_) out.push_back({dir.reference, dir.window});
  return out;
}

void RigStereo::setSolveWindows(bool on) {
  if (on == windows_) return;
  windows_ = on;
  buildDirections();
}

// The reference's image as its direction solves it: the whole image, or a copy of the window.
const ImageF& RigStereo::referenceImage(Direction& dir, const std::vector<ImageF>& images) {
  const ImageF& image = images[size_t(dir.reference)];
  const ImageWindow& w = dir.window;
  if (w.x0 == 0 && w.y0 == 0 && w.width == image.width && w.height == image.height) return image;
  if (dir.windowImage.width != w.width || dir.windowImage.height != w.height)
    dir.windowImage = ImageF(w.width, w.height);
  for (int y = 0; y < w.height; ++y) {
    const float* row = &image.data[size_t(w.y0 + y) * size_t(image.width) + size_t(w.x0)];
    std::copy(row, row + w.width, &dir.windowImage.data[size_t(y) * size_t(w.width)]);
  }
  return dir.windowImage;
}

// A camera's fused result computes its own z and points from its depth, so the directions
// never return theirs; the fusion needs their confidence.
void RigStereo::applyOutputs() {
  for (Direction& dir : directions_) dir.stereo->setOutputs({flow_, flow_, false, true});
}

void RigStereo::setPointOutputs(bool on) { points_ = on; }

void RigStereo::setFlowOutputs(bool on) {
  flow_ = on;
  applyOutputs();
}

RigStereo::~RigStereo() = default;

// The pair of direction d's reference and partner, each camera the window its direction
// solves (d's and `back`'s), for the cross-check between their estimates.
Rig RigStereo::windowPair(size_t d, size_t back) const {
  Rig pair = pairRig(rig_, directions_[d].reference, directions_[d].other);
  const ImageWindow& a = directions_[d].window;
  const ImageWindow& b = directions_[back].window;
  pair.cam0 = pair.cam0.cropped(a.x0, a.y0, a.width, a.height);
  pair.cam1 = pair.cam1.cropped(b.x0, b.y0, b.width, b.height);
  return pair;
}

void RigStereo::setCrossCheck(double tolerance) {
  if (!(tolerance >= 0 && tolerance <= 1)) throw Error("cross-check tolerance must be in [0, 1]");
  if (tolerance > 0 && oneWay_) throw Error(kOneWayCrossCheck);
  crossCheck_ = tolerance;
}

void RigStereo::setConcurrentSolves(bool on) { concurrent_ = on; }

std::string RigStereo::backendName() const { return directions_.front().stereo->backendName(); }

RigResult RigStereo::compute(const std::vector<ImageF>& images) {
  RigResult out;
  compute(images, out);
  return out;
}

void RigStereo::compute(const std::vector<ImageF>& images, RigResult& out) {
  solveAll(images, out, [&](Direction& dir, DepthResult& estimate) {
    dir.stereo->compute(referenceImage(dir, images), images[size_t(dir.other)], estimate);
  });
}

RigResult RigStereo::next(const std::vector<ImageF>& images, const Pose* bodyPose) {
  RigResult out;
  next(images, out, bodyPose);
  return out;
}

void RigStereo::next(const std::vector<ImageF>& images, RigResult& out, const Pose* bodyPose) {
  solveAll(images, out, [&](Direction& dir, DepthResult& estimate) {
    Pose camera;  // T_world_cam = T_world_body * T_body_cam
    if (bodyPose) {
      const BodyPose& inBody = rig_.poses[size_t(dir.reference)];
      camera.R = bodyPose->R * inBody.R;
      camera.t = bodyPose->R * inBody.p + bodyPose->t;
    }
    dir.stereo->next(referenceImage(dir, images), images[size_t(dir.other)], estimate, bodyPose ? &camera : nullptr);
  });
}

void RigStereo::resetSequence() {
  for (Direction& dir : directions_) dir.stereo->resetSequence();
}

// Every direction through `solve`, concurrently (each Stereo is independent: test_threads):
// a GPU backend's solves then overlap on the device, each on its own stream or queue, where one
// 848x800 solve leaves most of a large GPU idle between its small kernels. The first error
// (in direction order) is rethrown once all have finished.
template <class Solve>
void RigStereo::solveDirections(Solve& solve, const std::vector<ImageF>& images) {
  std::vector<std::exception_ptr> errors(directions_.size());
  // Without a cross-check to change them after, each estimate goes into the panorama as its
  // solve ends: its upload and placing overlap the solves still running.
  const bool placeEarly = panorama_ && crossCheck_ == 0;
  auto run = [&](size_t d) {
    try {
      solve(directions_[d], estimates_[d]);
      if (placeEarly) panorama_->placeView(d, estimates_[d], &images[size_t(directions_[d].reference)]);
    } catch (...) {
      errors[d] = std::current_exception();
    }
  };
  if (!concurrent_) {
    for (size_t d = 0; d < directions_.size(); ++d) run(d);
  } else {
    std::vector<std::thread> workers;
    for (size_t d = 1; d < directions_.size(); ++d) workers.emplace_back(run, d);
    run(0);
    for (std::thread& w : workers) w.join();
  }
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

// Camera k's result from the directions that solve from it; all invalid where there are none
// (one way: a camera may be no pair's reference). One way, the pixels without an estimate of
// their own are completed from the partners that solved toward it.
void RigStereo::fuseCamera(int k, DepthResult& out) const {
  std::vector<PlacedEstimate> mine;
  for (size_t d = 0; d < directions_.size(); ++d)
    if (directions_[d].reference == k) mine.push_back({&estimates_[d], directions_[d].window});
  const Camera& cam = rig_.cameras[size_t(k)];
  if (!mine.empty())
    fuseCameraEstimates(cam, mine, rays_[size_t(k)], out, points_);
  else
    invalidCamera(cam, out);
  if (!oneWay_) return;
  // Open: no estimate of its own, outside its windows or inside them where its partner saw
  // nothing (a window is a bounding box).
  std::vector<uint8_t> open(out.valid.data.size());
  for (size_t p = 0; p < open.size(); ++p) open[p] = out.valid.data[p] == 0;
  for (size_t d = 0; d < directions_.size(); ++d)
    if (directions_[d].other == k) {
      const int from = directions_[d].reference;
      completeFromPartner(pairRig(rig_, from, k), {&estimates_[d], directions_[d].window}, rays_[size_t(from)],
                          rays_[size_t(k)], open, out);
    }
}

// A camera with no estimate: every output it carries NaN (valid 0).
void RigStereo::invalidCamera(const Camera& cam, DepthResult& out) const {
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();
  out = DepthResult();
  out.valid = ImageU8(cam.width, cam.height, 0);
  out.depth.radial = out.confidence = ImageF(cam.width, cam.height, nan);
  out.depth.z = points_ ? ImageF(cam.width, cam.height, nan) : ImageF();
  out.depth.points = points_ ? Image<Point3f>(cam.width, cam.height, {nan, nan, nan}) : Image<Point3f>();
  out.disparity = flow_ ? ImageF(cam.width, cam.height, nan) : ImageF();
  out.warp = flow_ ? FlowImage(cam.width, cam.height, {nan, nan}) : FlowImage();
}

// Every direction through `solve`, then the cross-check and the per-camera fusion.
template <class Solve>
void RigStereo::solveAll(const std::vector<ImageF>& images, RigResult& out, Solve&& solve) {
  if (int(images.size()) != rig_.size())
    throw Error("a rig of " + std::to_string(rig_.size()) + " cameras needs " + std::to_string(rig_.size()) +
                " images, got " + std::to_string(images.size()));
  for (int k = 0; k < rig_.size(); ++k) {  // named by camera here, not by a pair direction's left and right
    const ImageF& image = images[size_t(k)];
    const Camera& cam = rig_.cameras[size_t(k)];
    if (image.width != cam.width || image.height != cam.height)
      throw Error("cam" + std::to_string(k) + "'s image is " + std::to_string(image.width) + "x" +
                  std::to_string(image.height) + " but the camera is " + std::to_string(cam.width) + "x" +
                  std::to_string(cam.height));
  }
  const auto start = std::chrono::steady_clock::now();
  solveDirections(solve, images);  // into estimates_, reused: a frame allocates nothing
  const auto solvedAt = std::chrono::steady_clock::now();
  out.solves.clear();
  for (size_t d = 0; d < directions_.size(); ++d) {
    const Direction& dir = directions_[d];
    out.solves.push_back(
        {dir.reference, dir.other, dir.window, estimates_[d].totalMs, 0, estimates_[d].warm, estimates_[d].redone});
  }
  if (crossCheck_ > 0) {
    // Against the other directions as solved, not as already checked; each on its window.
    const std::vector<DepthResult> solved = estimates_;
    for (size_t d = 0; d < directions_.size(); ++d)
      for (size_t back = 0; back < directions_.size(); ++back)
        if (directions_[back].reference == directions_[d].other && directions_[back].other == directions_[d].reference)
          out.solves[d].crossCheckInvalidated =
              crossCheck(windowPair(d, back), estimates_[d], solved[back], crossCheck_);
  }
  if (panorama_) {
    const auto panoramaStart = std::chrono::steady_clock::now();
    if (crossCheck_ > 0)
      for (size_t d = 0; d < directions_.size(); ++d)
        panorama_->placeView(d, estimates_[d], &images[size_t(directions_[d].reference)]);
    panorama_->finish(out.panorama, panoramaMinConfidence_);
    out.panoramaMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - panoramaStart).count();
  } else {
    out.panorama = Panorama();
    out.panoramaMs = 0;
  }
  if (cameraOutputs_) {
    out.cameras.resize(size_t(rig_.size()));
    for (int k = 0; k < rig_.size(); ++k) fuseCamera(k, out.cameras[size_t(k)]);
  } else {
    out.cameras.clear();
  }
  // The estimates go out as the views, and the caller's previous ones come back to be
  // solved into: no copy, and a loop that reuses its RigResult allocates nothing.
  out.views.swap(estimates_);
  estimates_.resize(directions_.size());
  const auto end = std::chrono::steady_clock::now();
  out.totalMs = std::chrono::duration<double, std::milli>(end - start).count();
  out.fusionMs = std::chrono::duration<double, std::milli>(end - solvedAt).count();
}

}  // namespace cs

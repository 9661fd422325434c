// RigStereo (rig_stereo.hpp): a rig's pairs through Stereo, then the per-camera fusion.
#include "curvestereo/rig_stereo.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "curvestereo/rig_fusion.hpp"
#include "curvestereo/stereo.hpp"

namespace cs {

Params rigParams(const CameraRig& rig, Params params) {
  double widest = 0;
  for (const Camera& cam : rig.cameras) widest = std::max(widest, viewHalfAngle(cam));
  // Rounded down to a micro-degree: never wider than the widest lens.
  params.maxFovDeg = std::max(params.maxFovDeg, std::floor(2.0 * widest * 180.0 / M_PI * 1e6) / 1e6);
  return params;
}

RigStereo::RigStereo(const CameraRig& rig, const std::vector<PairInfo>& pairs, const Params& params,
                     const std::string& backend)
    : rig_(rig) {
  rig_.validate();
  std::vector<bool> covered(size_t(rig.size()), false);
  for (const PairInfo& p : pairs)
    for (const auto& [a, b] : {std::pair{p.i, p.j}, std::pair{p.j, p.i}}) {
      directions_.push_back({a, b, std::make_unique<Stereo>(pairRig(rig_, a, b), params, backend)});
      covered[size_t(a)] = true;
    }
  for (int k = 0; k < rig.size(); ++k)
    if (!covered[size_t(k)]) throw Error("cam" + std::to_string(k) + " is in none of the pairs to solve");
}

RigStereo::~RigStereo() = default;

void RigStereo::setCrossCheck(double tolerance) {
  if (!(tolerance >= 0 && tolerance <= 1)) throw Error("cross-check tolerance must be in [0, 1]");
  crossCheck_ = tolerance;
}

std::string RigStereo::backendName() const { return directions_.front().stereo->backendName(); }

RigResult RigStereo::compute(const std::vector<ImageF>& images) {
  return solveAll(images, [&](Direction& dir, DepthResult& out) {
    dir.stereo->compute(images[size_t(dir.reference)], images[size_t(dir.other)], out);
  });
}

RigResult RigStereo::next(const std::vector<ImageF>& images, const Pose* bodyPose) {
  return solveAll(images, [&](Direction& dir, DepthResult& out) {
    Pose camera;  // T_world_cam = T_world_body * T_body_cam
    if (bodyPose) {
      const BodyPose& inBody = rig_.poses[size_t(dir.reference)];
      camera.R = bodyPose->R * inBody.R;
      camera.t = bodyPose->R * inBody.p + bodyPose->t;
    }
    dir.stereo->next(images[size_t(dir.reference)], images[size_t(dir.other)], out, bodyPose ? &camera : nullptr);
  });
}

void RigStereo::resetSequence() {
  for (Direction& dir : directions_) dir.stereo->resetSequence();
}

// Every direction through `solve`, then the cross-check and the per-camera fusion.
template <class Solve>
RigResult RigStereo::solveAll(const std::vector<ImageF>& images, Solve&& solve) {
  if (int(images.size()) != rig_.size())
    throw Error("a rig of " + std::to_string(rig_.size()) + " cameras needs " + std::to_string(rig_.size()) +
                " images, got " + std::to_string(images.size()));
  const auto start = std::chrono::steady_clock::now();
  RigResult out;
  std::vector<DepthResult> estimates(directions_.size());
  for (size_t d = 0; d < directions_.size(); ++d) {
    Direction& dir = directions_[d];
    solve(dir, estimates[d]);
    out.solves.push_back({dir.reference, dir.other, estimates[d].totalMs, 0, estimates[d].warm, estimates[d].redone});
  }
  if (crossCheck_ > 0) {
    // Against the other directions as solved, not as already checked.
    const std::vector<DepthResult> solved = estimates;
    for (size_t d = 0; d < directions_.size(); ++d)
      for (size_t back = 0; back < directions_.size(); ++back)
        if (directions_[back].reference == directions_[d].other && directions_[back].other == directions_[d].reference)
          out.solves[d].crossCheckInvalidated = crossCheck(
              pairRig(rig_, directions_[d].reference, directions_[d].other), estimates[d], solved[back], crossCheck_);
  }
  for (int k = 0; k < rig_.size(); ++k) {
    std::vector<const DepthResult*> mine;
    for (size_t d = 0; d < directions_.size(); ++d)
      if (directions_[d].reference == k) mine.push_back(&estimates[d]);
    out.cameras.push_back(fuseCameraEstimates(rig_.cameras[size_t(k)], mine));
  }
  out.totalMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace cs

// A rig's recorded sequence: ASL folders with N cameras (rig_sequence.hpp).
#include "curvestereo/rig_sequence.hpp"

#include <algorithm>
#include <filesystem>

#include "calib_common.hpp"
#include "curvestereo/image_io.hpp"
#include "sequence_pairing.hpp"

namespace cs {
namespace {

namespace fs = std::filesystem;
using calib::oneLine;

std::string cam(int k) { return "cam" + std::to_string(k); }

// T_world_body from camera 0's pose in the world: T_world_cam0 * inverse(T_body_cam0).
Pose bodyPoseFrom(const Pose& worldCam0, const BodyPose& cam0OnBody) {
  Pose body;
  body.R = worldCam0.R * cam0OnBody.R.transpose();
  body.t = worldCam0.t - body.R * cam0OnBody.p;
  return body;
}

}  // namespace

int RigSequence::camerasIn(const std::string& source) {
  const fs::path mav0 = detail::aslMav0(source);
  if (mav0.empty()) return 0;
  std::error_code ec;
  int k = 0;
  while (fs::is_regular_file(mav0 / cam(k) / "data.csv", ec)) ++k;
  return k;
}

RigSequence RigSequence::open(const std::string& source, const CameraRig& rig, const SequenceOptions& options) {
  const int cameras = rig.size();
  if (cameras < 2) throw Error("a rig sequence needs at least two cameras, got " + std::to_string(cameras));
  detail::checkTolerances(options);
  const fs::path mav0 = detail::aslMav0(source);
  if (mav0.empty()) throw Error(oneLine("'" + source + "' is not an ASL/EuRoC folder (no mav0/cam0/ or cam0/ in it)"));
  std::vector<std::vector<AslRow>> rows;
  for (int k = 0; k < cameras; ++k) rows.push_back(detail::readAslCamera(mav0, cam(k)));
  RigSequence seq;
  seq.cameras_ = cameras;
  // partner[k][i]: camera k's image paired with camera 0's image i, or -1.
  const std::vector<int64_t> reference = detail::timesOf(rows[0]);
  std::vector<std::vector<long long>> partner(size_t(cameras), std::vector<long long>(reference.size(), -1));
  for (size_t i = 0; i < reference.size(); ++i) partner[0][i] = (long long)i;
  const std::string within = " within " + detail::msText(options.pairToleranceMs);
  for (int k = 1; k < cameras; ++k) {
    const detail::TimePairs paired =
        detail::pairByTime(reference, detail::timesOf(rows[size_t(k)]), options.pairToleranceMs);
    for (const auto& [i, j] : paired.pairs) partner[size_t(k)][i] = (long long)j;
    for (size_t j : paired.rightAlone)
      seq.warnings_.push_back(cam(k) + " " + rows[size_t(k)][j].filename + ": no cam0 frame" + within);
    seq.unpaired_ += paired.rightAlone.size();
  }
  for (size_t i = 0; i < reference.size(); ++i) {
    RigSequenceFrame f;
    f.timestampNs = reference[i];
    for (int k = 0; k < cameras && f.paths.size() == size_t(k); ++k)
      if (partner[size_t(k)][i] >= 0)
        f.paths.push_back((mav0 / cam(k) / "data" / rows[size_t(k)][size_t(partner[size_t(k)][i])].filename).string());
    if (f.paths.size() == size_t(cameras)) {
      seq.frames_.push_back(std::move(f));
      continue;
    }
    // Camera 0's image and every partner it has go unused: name the first camera missing.
    seq.warnings_.push_back("cam0 " + rows[0][i].filename + ": no " + cam(int(f.paths.size())) + " frame" + within);
    for (int k = 0; k < cameras; ++k) seq.unpaired_ += partner[size_t(k)][i] >= 0;
  }
  if (seq.frames_.empty())
    throw Error(oneLine("ASL folder '" + mav0.string() + "': no frame has an image of all " + std::to_string(cameras) +
                        " cameras" + within));
  const std::string posesPath = options.poses.empty() ? detail::aslPoses(source, mav0) : options.poses;
  if (!posesPath.empty()) {
    seq.posesGiven_ = true;
    const std::map<int64_t, Pose> poses = readPoses(posesPath);
    std::vector<int64_t> missing;
    for (RigSequenceFrame& f : seq.frames_) {
      const Pose* pose = detail::nearestPose(poses, f.timestampNs, options.poseToleranceMs);
      if (pose) f.hasPose = true, f.bodyPose = bodyPoseFrom(*pose, rig.poses[0]);
      if (!pose) missing.push_back(f.timestampNs);
    }
    if (!missing.empty())
      seq.warnings_.push_back(
          detail::missingPosesText(missing, seq.frames_.size(), options.poseToleranceMs, posesPath));
  }
  return seq;
}

std::string RigSequence::summary() const {
  const size_t posed = size_t(std::count_if(frames_.begin(), frames_.end(), [](const auto& f) { return f.hasPose; }));
  return std::to_string(frames_.size()) + " frames of " + std::to_string(cameras_) + " cameras (ASL, " +
         (posesGiven_ ? std::to_string(posed) + " with poses" : std::string("no poses")) + "); " +
         std::to_string(unpaired_) + " images unpaired";
}

void RigSequence::load(size_t i, std::vector<ImageF>& images) const {
  if (i >= frames_.size())
    throw Error("rig sequence frame " + std::to_string(i) + " does not exist (" + std::to_string(frames_.size()) +
                " frames)");
  const RigSequenceFrame& f = frames_[i];
  images.resize(f.paths.size());
  for (size_t k = 0; k < f.paths.size(); ++k) {
    try {
      images[k] = readPngGray(f.paths[k]);
    } catch (const Error& e) {  // e names the file
      throw Error(oneLine("frame " + std::to_string(i) + " (t " + std::to_string(f.timestampNs) + " ns), " +
                          cam(int(k)) + " image: " + e.what()));
    }
  }
}

}  // namespace cs

// Recorded sequences of a rig of N cameras: an ASL/EuRoC folder with one cam<k> per camera
// (mav0/cam0/data.csv ... mav0/cam<N-1>/data.csv, each "#timestamp [ns],filename" with its
// images in cam<k>/data/), as a multi-camera recording is written. Each frame is one image of
// every camera, paired to camera 0's by timestamp; the optional poses file holds camera 0's
// poses (T_world_cam0), as for a pair's sequence (sequence.hpp), and each frame carries the
// rig's, T_world_body = T_world_cam0 * T_body_cam0^-1 (what RigStereo::next takes).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "curvestereo/camera_rig.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/pose.hpp"
#include "curvestereo/sequence.hpp"

namespace cs {

struct RigSequenceFrame {          // one frame of every camera, not yet read
  int64_t timestampNs = 0;         // camera 0's
  std::vector<std::string> paths;  // per camera
  bool hasPose = false;
  Pose bodyPose;  // T_world_body when hasPose
};

class RigSequence {
 public:
  // source: the folder holding mav0/, or mav0/ itself, with cam0 ... cam<N-1> for the N
  // cameras of `rig` (whose camera 0 pose on the body turns the poses into the rig's). Camera
  // k's images are paired to camera 0's as a pair sequence pairs cam1's (mutual nearest
  // within options.pairToleranceMs); a camera-0 image without a partner in every camera is
  // no frame, and each image left out is named in warnings(). Poses: options.poses, else the
  // folder's poses_cam0.csv when it has one. Throws cs::Error, one line naming the problem:
  // fewer than two cameras, a missing cam<k>/data.csv, a malformed line, no complete frame.
  static RigSequence open(const std::string& source, const CameraRig& rig, const SequenceOptions& options = {});

  // How many cameras the ASL folder `source` (or its mav0/) records: cam0, cam1, ... up to
  // the first missing cam<k>/data.csv; 0 when it is no ASL folder. A pair sequence has 2, a
  // rig's more. Reads no file.
  static int camerasIn(const std::string& source);

  const std::vector<RigSequenceFrame>& frames() const { return frames_; }
  int cameras() const { return cameras_; }
  // One line each: every image that is in no frame ("cam2 1000033333333.png: no cam0 frame
  // within 1 ms"), frames without a pose although poses were given.
  const std::vector<std::string>& warnings() const { return warnings_; }
  // "16 frames of 4 cameras (ASL, 16 with poses); 0 images unpaired"
  std::string summary() const;

  // Frame i's images, float grey in [0, 1] (as Sequence::load reads them), one per camera.
  // Throws cs::Error naming the frame, its timestamp, the camera and the file when a file is
  // missing or unreadable. Thread-safe.
  void load(size_t i, std::vector<ImageF>& images) const;

 private:
  std::vector<RigSequenceFrame> frames_;
  std::vector<std::string> warnings_;
  int cameras_ = 0;
  bool posesGiven_ = false;
  size_t unpaired_ = 0;
};

}  // namespace cs

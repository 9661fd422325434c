// `curvestereo synth --sequence`: a stereo rig walking through one procedural scene,
// rendered frame by frame with exact ground truth, written in the EuRoC / ASL layout of
// ../shared/data/sequences (images, radial depth, masks of the moving object, poses of
// camera 0, Kalibr camchain).
//
// Motion of camera 0 (frame k at t = k / fps seconds, starting at the scene's viewpoint):
//   heading: R(k) = Rz(turn * t) * R(0), a turn about the world vertical (> 0: to the left,
//            counter-clockwise seen from above);
//   nominal centre: c(k + 1) = c(k) + (speed / fps) * R(k) e_z (forward along the camera's
//            own optical axis, then the turn);
//   walking bob: the centre is raised by bob * sin(2 pi bobHz t) along the camera's up
//            axis, -R(k) e_y (so frame 0 sits exactly at the viewpoint).
// Camera 1 keeps the rig's pose relative to camera 0. Everything is static except one box
// (0.3-0.4 m, resting on the ground) that crosses the view 2-3 m ahead at about 1 m/s; it
// is part of every depth map and has its own mask per camera. Deterministic per seed.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "synth/photometry.hpp"
#include "synth/scene.hpp"

namespace cs::synth {

struct SequenceConfig {
  SynthConfig render;         // scene, seed, cameras or rig, samples, field of view, nearest
  int frames = 12;            // 1..100000
  double fps = 30.0;          // (0, 10000]
  double speed = 1.0;         // m/s along camera 0's +z, [0, 50]
  double turnDegPerS = 20.0;  // about the world vertical, > 0 turns left, |turn| <= 720
  double bobM = 0.01;         // walking bob amplitude (m), [0, 0.5]
  double bobHz = 1.7;         // >= 0
  bool mover = true;

  // Throws cs::Error with one line naming the first bad value (as its CLI option).
  void validate() const;
};

// The moving object: a box resting on the ground (z = 0), turned about the vertical to
// face its direction of travel, moving at a constant horizontal velocity.
struct Mover {
  Eigen::Vector3d start = Eigen::Vector3d::Zero();  // centre at t = 0 (world)
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d halfSize = Eigen::Vector3d::Constant(0.175);
  double yaw = 0.0;  // rad, about world z
  Material material;

  Eigen::Vector3d centreAt(double seconds) const { return start + seconds * velocity; }
  Shape shapeAt(double seconds) const;
};

// 1000000000000 + round(frame * 1e9 / fps): the ASL timestamp (ns) of a frame.
int64_t sequenceTimestampNs(int frame, double fps);

struct SequenceFrame {
  int index = 0;
  int64_t timestampNs = 0;
  SynthPair pair;                // images, depth (mover included), pose0 / pose1, this frame's scene
  ImageF moverLeft, moverRight;  // 1 where the pixel-centre ray hits the mover, else 0 (empty without one)
};

// Plans a sequence (scene, poses, mover path) on construction; renders one frame at a
// time. Throws cs::Error for a bad config, a walk that runs into the scene, or a scene
// with no free path for the mover.
class SequenceRenderer {
 public:
  explicit SequenceRenderer(const SequenceConfig& cfg);

  const SequenceConfig& config() const { return cfg_; }
  int frames() const { return cfg_.frames; }
  double seconds(int frame) const { return frame / cfg_.fps; }
  const Rig& rig() const { return rig_; }
  const Scene& staticScene() const { return scene_; }                       // without the mover
  const Pose& pose0(int frame) const { return poses0_.at(size_t(frame)); }  // T_world_cam0
  Pose pose1(int frame) const;                                              // T_world_cam1
  const std::optional<Mover>& mover() const { return mover_; }

  // progress: fraction of this frame, left view in [0, 0.5], right in [0.5, 1].
  SequenceFrame render(int frame, const ProgressCallback& progress = {}) const;

 private:
  SequenceConfig cfg_;
  Rig rig_;
  Scene scene_;
  std::vector<Pose> poses0_;
  std::optional<Mover> mover_;
};

// ---------------------------------------------------------------- the folder

struct SequenceFrameReport {
  int index = 0;
  int64_t timestampNs = 0;
  double seconds = 0.0;                            // render + camera model + writing
  double moverShare[2] = {0.0, 0.0};               // mask pixels / valid pixels, camera 0 and 1
  double moverNearest = 0.0, moverFarthest = 0.0;  // depth range of the mask pixels (both cameras), 0 if none
  double nearest = 0.0;                            // nearest depth of camera 0
};

struct SequenceReport {
  int frames = 0;
  double seconds = 0.0;
  double exposureScale = 1.0;  // the camera model's, fixed at frame 0 (1 without a model)
  double pathLength = 0.0;     // metres travelled by camera 0
  double headingChangeDeg = 0.0;
  int moverFrames = 0;  // frames where camera 0 sees the mover
  double moverNearest = 0.0, moverFarthest = 0.0, moverShareMax = 0.0;
  std::vector<SequenceFrameReport> perFrame;
};

struct SequenceCallbacks {
  std::function<void(int frame, double fraction)> rendering;  // within one frame
  std::function<void(const SequenceFrameReport&)> frameDone;
};

// Renders every frame through the camera model (its parameters and exposure fixed for
// the sequence, fresh noise per image) and writes, under dir:
//   mav0/cam0/data/<t>.png, mav0/cam0/data.csv ("#timestamp [ns],filename"),
//   mav0/cam0/sensor.yaml, cam1 alike; mav0/depth0/data/<t>.exr (radial depth, +inf sky,
//   0 outside the image circle) with data.csv, depth1 alike; with a mover,
//   mav0/mover0/data/<t>.png (255 where camera 0's pixel sees it) with data.csv, mover1
//   alike; poses_cam0.csv ("#timestamp [ns],px,py,pz,qx,qy,qz,qw", T_world_cam0);
//   camchain.yaml (Kalibr); meta.json; photometry.json when the camera model is on.
SequenceReport writeSequence(const SequenceRenderer& renderer, const CameraPhotometry& camera, const std::string& dir,
                             const SequenceCallbacks& callbacks = {});

}  // namespace cs::synth

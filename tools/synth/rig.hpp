// `curvestereo synth --rig LAYOUT`: an N-camera fisheye rig in one procedural scene, with
// each camera's ground-truth depth and the 360-degree range panorama around the rig, in the
// folder layout of ../shared/data/rigs (README there): what `curvestereo eval RIGDIR` scores
// and `run --calib camchain.yaml cam0.png ...` reads.
//
// Body frame: x right, y down, z forward, origin the rig centre. It is the panorama frame
// that run and eval derive from the cameras alone (rig_fusion.hpp's panoramaFrame: the
// cameras' mean y axis down, camera 0's axis made level forward, the mean centre), so that
// the truth and the estimate share one grid.
#pragma once
#include <string>
#include <vector>

#include "curvestereo/camera_rig.hpp"
#include "synth/scene.hpp"

namespace cs::synth {

// A layout: every camera's model, its pose on the body (camera-to-body) and the field of
// view it is rendered with.
struct RigLayout {
  std::string name, description;
  CameraRig rig;
  double maxFovDeg = 180;
};

// The layouts, cameras `size` pixels square (equidistant Kannala-Brandt, image circle
// touching the borders); yaw > 0 turns a camera toward +x, pitch > 0 up:
//   back2  two 220-degree fisheyes back to back (yaw 0 and 180), 12 cm apart along z
//   ring4  four 180-degree fisheyes, yaw 0 / 90 / 180 / 270, pitched 5 deg down, 8 cm out
//          from the centre along their viewing directions (a 16 cm square, rig4_urban_dev)
//   ring6  six 180-degree fisheyes in two triples: yaw 0 / 120 / 240 pitched 30 deg up and
//          4 cm above the centre, yaw 60 / 180 / 300 pitched 30 deg down and 4 cm below,
//          each 8 cm out horizontally; cameras numbered by yaw (up, down, up, ...)
// Throws cs::Error (one line, naming the layouts) for any other name.
RigLayout rigLayout(const std::string& name, int size);
extern const char* const kRigLayoutNames;  // "back2, ring4 or ring6"

struct RigConfig {
  std::string layout = "ring4";
  std::string scene = "urban";  // urban | indoor
  uint32_t seed = 1;
  int size = 800;  // every camera's image side
  int samplesPerAxis = 3;
  double nearest = 1.0;  // metres from camera 0 to its nearest object; every camera gets one near it
  int panoramaWidth = 2048;
};

struct SynthRig {
  RigLayout layout;
  std::vector<ImageF> images, depths;  // per camera: renderView's image and radial depth
  ImageF panorama, panoramaRange;      // from the body origin, in the body frame
  Pose body;                           // body-to-world
  Scene scene;
};

// Checks the config (one-line cs::Error), builds a scene around the rig and renders every
// camera, then the panorama. progress: the fraction of all rendering done, in [0, 1].
SynthRig renderRig(const RigConfig& cfg, const ProgressCallback& progress = {});

// cam<k>.png (8-bit grey), depth<k>.exr, camchain.yaml (Kalibr, T_cn_cnm1 chain),
// panorama_range.exr, panorama.png and rig.json (T_world_body, T_body_cam<k>, the
// panorama convention, the render settings) into dir (created).
void writeRigFolder(const SynthRig& rig, const RigConfig& cfg, const std::string& dir);

}  // namespace cs::synth

// Rendering an N-camera rig with ground truth per camera and for the panorama (rig.hpp).
#include "synth/rig.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "curvestereo/image_io.hpp"
#include "curvestereo/rig_fusion.hpp"
#include "synth/json_text.hpp"

namespace cs::synth {

const char* const kRigLayoutNames = "back2, ring4 or ring6";

namespace {

namespace fs = std::filesystem;
using Eigen::Matrix3d;
using Eigen::Vector3d;

double radians(double deg) { return deg * M_PI / 180.0; }

// Equidistant Kannala-Brandt whose fovDeg image circle touches the borders of a size x size
// image (defaultFisheye's model, for any field of view).
Camera equidistantFisheye(int size, double fovDeg) {
  const double f = size / radians(fovDeg), c = 0.5 * (size - 1);
  return Camera::kannalaBrandt4(size, size, f, f, c, c);
}

// Entries below 1e-12 in magnitude set to 0: exact zeros at multiples of 90 degrees and at the
// centre, as in the dev rig's files, instead of rounding residue.
template <class Matrix>
Matrix snapped(const Matrix& m) {
  return m.unaryExpr([](double v) { return std::abs(v) < 1e-12 ? 0.0 : v; });
}

// R_body_cam = Ry(yaw) Rx(pitch) (rigs/README's rotation_definition, no roll): yaw about the
// body y axis (> 0 turns the optical axis toward +x), then pitch about the camera's x axis
// (> 0 looks up, toward -y). The camera sits `out` metres from the body's y axis along its
// horizontal viewing direction, `height` metres along body y (> 0: below the centre).
BodyPose mountedPose(double yawDeg, double pitchDeg, double out, double height) {
  BodyPose pose;
  pose.R = Eigen::AngleAxisd(radians(yawDeg), Vector3d::UnitY()).toRotationMatrix() *
           Eigen::AngleAxisd(radians(pitchDeg), Vector3d::UnitX()).toRotationMatrix();
  pose.p = Vector3d(out * std::sin(radians(yawDeg)), height, out * std::cos(radians(yawDeg)));
  return pose;
}

// Re-expresses the poses in the panorama frame that run and eval derive from the rig, so that
// the body frame is that frame exactly (the layouts are built symmetric: this only moves them
// by rounding residue, which snapping then removes).
void toPanoramaFrame(CameraRig& rig) {
  const PanoramaFrame frame = panoramaFrame(rig);
  for (BodyPose& pose : rig.poses) {
    pose.R = snapped<Matrix3d>(frame.R.transpose() * pose.R);
    pose.p = snapped<Vector3d>(frame.R.transpose() * (pose.p - frame.centre));
  }
}

RigLayout makeLayout(const std::string& name, const std::string& description, const Camera& camera, double maxFovDeg,
                     const std::vector<BodyPose>& poses) {
  RigLayout layout;
  layout.name = name;
  layout.description = description;
  layout.maxFovDeg = maxFovDeg;
  layout.rig.cameras.assign(poses.size(), camera);
  layout.rig.poses = poses;
  toPanoramaFrame(layout.rig);
  layout.rig.validate();
  return layout;
}

// Per camera k, its pose in the world: the body's pose composed with the camera's on it.
Pose cameraPose(const Pose& body, const BodyPose& onBody) {
  Pose pose;
  pose.rotation = body.rotation * onBody.R;
  pose.centre = body.centre + body.rotation * onBody.p;
  return pose;
}

// The scene generator places the body where it places camera 0 for a pair (nearly level), and
// the cameras on it, so that clutter keeps clear of every camera and every camera gets a near
// object.
SceneSpec sceneSpec(const RigConfig& cfg, const CameraRig& rig) {
  SceneSpec spec;
  spec.kind = cfg.scene;
  spec.seed = cfg.seed;
  spec.nearest = cfg.nearest;
  spec.pixelAngle = 2.0 * M_PI / cfg.panoramaWidth;
  for (int k = 0; k < rig.size(); ++k) {
    spec.pixelAngle = std::min(spec.pixelAngle, pixelAngle(rig.cameras[size_t(k)]));
    const BodyPose& pose = rig.poses[size_t(k)];
    spec.rigCameras.push_back(Pose{pose.R, pose.p});
  }
  return spec;
}

void checkRigConfig(const RigConfig& cfg) {
  if (cfg.size < 16 || cfg.size > 16384) throw Error("synth: the image size must be 16..16384 pixels");
  if (cfg.panoramaWidth < 4 || cfg.panoramaWidth > 32768 || cfg.panoramaWidth % 2 != 0)
    throw Error("synth: the panorama width must be even and in 4..32768 pixels");
  SynthConfig pair;  // the checks a pair's render makes of the shared settings
  pair.samplesPerAxis = cfg.samplesPerAxis;
  pair.nearest = cfg.nearest;
  checkSynthConfig(pair);
}

}  // namespace

RigLayout rigLayout(const std::string& name, int size) {
  if (name == "back2")
    return makeLayout(name, "two 220 deg fisheyes back to back, 12 cm apart", equidistantFisheye(size, 220.0), 220.0,
                      {mountedPose(0, 0, 0.06, 0), mountedPose(180, 0, 0.06, 0)});
  if (name == "ring4") {
    std::vector<BodyPose> poses;
    for (double yaw : {0, 90, 180, 270}) poses.push_back(mountedPose(yaw, -5, 0.08, 0));
    return makeLayout(name, "four 180 deg fisheyes facing front / right / back / left on a 16 cm square, 5 deg down",
                      equidistantFisheye(size, 180.0), 180.0, poses);
  }
  if (name == "ring6") {
    std::vector<BodyPose> poses;
    for (int k = 0; k < 6; ++k) {
      const bool up = k % 2 == 0;
      poses.push_back(mountedPose(60.0 * k, up ? 30 : -30, 0.08, up ? -0.04 : 0.04));
    }
    return makeLayout(name, "six 180 deg fisheyes: a triple 30 deg up, 4 cm high, and one 30 deg down, 60 deg between",
                      equidistantFisheye(size, 180.0), 180.0, poses);
  }
  throw Error("synth: unknown rig layout '" + name + "' (expected " + kRigLayoutNames + ")");
}

SynthRig renderRig(const RigConfig& cfg, const ProgressCallback& progress) {
  checkRigConfig(cfg);
  SynthRig out;
  out.layout = rigLayout(cfg.layout, cfg.size);
  const CameraRig& rig = out.layout.rig;
  out.scene = buildScene(sceneSpec(cfg, rig));
  out.body = out.scene.viewpoint;

  // Each camera and the panorama get an equal share of the progress.
  const int parts = rig.size() + 1;
  auto share = [&](int part) {
    return [&progress, part, parts](double f) {
      if (progress) progress((part + f) / parts);
    };
  };
  RenderOptions options;
  options.samplesPerAxis = cfg.samplesPerAxis;
  options.maxFovDeg = out.layout.maxFovDeg;
  out.images.resize(size_t(rig.size()));
  out.depths.resize(size_t(rig.size()));
  for (int k = 0; k < rig.size(); ++k)
    renderView(out.scene, rig.cameras[size_t(k)], cameraPose(out.body, rig.poses[size_t(k)]), options,
               out.images[size_t(k)], out.depths[size_t(k)], share(k));
  renderPanorama(out.scene, out.body, cfg.panoramaWidth, cfg.samplesPerAxis, out.panorama, out.panoramaRange,
                 share(rig.size()));
  return out;
}

namespace {

std::string rigJson(const SynthRig& r, const RigConfig& cfg) {
  using json::matrix4;
  using json::num;
  const CameraRig& rig = r.layout.rig;
  std::ostringstream j;
  j << "{\n \"name\": \"synth_" << r.layout.name << "\",\n \"generator\": \"curvestereo synth --rig " << r.layout.name
    << "\",\n \"layout\": \"" << r.layout.name << "\",\n \"description\": \"" << r.layout.description
    << "\",\n \"n_cameras\": " << rig.size() << ",\n";
  j << " \"body_frame\": \"x right, y down, z forward (OpenCV-style); origin = rig centre = panorama centre\",\n";
  j << " \"camera_frames\": \"OpenCV (x right, y down, z forward); T_body_camI maps camera-I coordinates to body "
       "coordinates (camera-to-body)\",\n";
  j << " \"world_frame\": \"z up, metres, ground at z = 0\",\n";
  j << " \"T_world_body\": " << matrix4(r.body.rotation, r.body.centre) << ",\n";
  for (int k = 0; k < rig.size(); ++k) {
    const BodyPose& pose = rig.poses[size_t(k)];
    j << " \"T_body_cam" << k << "\": " << matrix4(pose.R, pose.p) << ",\n";
  }
  j << " \"render\": {\"scene_type\": \"" << cfg.scene << "\", \"seed\": " << cfg.seed << ", \"width\": " << cfg.size
    << ", \"height\": " << cfg.size << ", \"camera\": \"" << rig.cameras.front().modelName()
    << "\", \"max_fov_deg\": " << num(r.layout.maxFovDeg) << ", \"samples_per_axis\": " << cfg.samplesPerAxis
    << ", \"nearest_m\": " << num(cfg.nearest) << "},\n";
  j << " \"depth\": \"depth<i>.exr: radial distance (m) from camera i's centre to the surface seen through the pixel "
       "centre; sky +inf; outside the image circle 0\",\n";
  j << " \"panorama\": {\n  \"file\": \"panorama_range.exr\",\n  \"image\": \"panorama.png\",\n  \"width\": "
    << r.panoramaRange.width << ",\n  \"height\": " << r.panoramaRange.height << ",\n";
  j << "  \"convention\": \"Equirectangular range map around the BODY origin, in the body frame. Pixel (col j, row "
       "i), 0-based, row 0 at the top: lon = -pi + 2 pi (j + 0.5) / W, lat = pi/2 - pi (i + 0.5) / H, direction d = "
       "(cos(lat) sin(lon), -sin(lat), cos(lat) cos(lon)): lon = 0 along +z, lon > 0 toward +x, lat > 0 toward -y "
       "(up). Value = Euclidean distance (m) from the body origin to the surface hit along d (X_body = range * d); "
       "sky = +inf; every pixel is traced (no 0 values).\",\n";
  j << "  \"centre\": \"body origin (T_world_body translation)\",\n  \"frame\": \"body (x right, y down, z "
       "forward)\"\n }\n}\n";
  return j.str();
}

std::string camFile(const char* stem, int k, const char* ext) { return stem + std::to_string(k) + ext; }

}  // namespace

void writeRigFolder(const SynthRig& r, const RigConfig& cfg, const std::string& dir) {
  const fs::path root(dir);
  fs::create_directories(root);
  for (int k = 0; k < r.layout.rig.size(); ++k) {
    writePngGray((root / camFile("cam", k, ".png")).string(), r.images[size_t(k)]);
    writeExr((root / camFile("depth", k, ".exr")).string(), r.depths[size_t(k)]);
  }
  saveKalibrRig(r.layout.rig, (root / "camchain.yaml").string());
  writeExr((root / "panorama_range.exr").string(), r.panoramaRange);
  writePngGray((root / "panorama.png").string(), r.panorama);
  json::writeText(root / "rig.json", rigJson(r, cfg));
}

}  // namespace cs::synth

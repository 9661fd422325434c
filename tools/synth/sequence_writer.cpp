// Writing a synthetic sequence in the EuRoC / ASL layout (sequence.hpp, writeSequence).
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "curvestereo/image_io.hpp"
#include "synth/json_text.hpp"
#include "synth/random.hpp"
#include "synth/sequence.hpp"

namespace cs::synth {
namespace {

namespace fs = std::filesystem;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using json::list;
using json::matrix4;
using json::num;
using json::vec;
using json::writeText;

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The scalar fields of camera `cam` ("cam0") in a camchain.yaml written by saveKalibr.
std::map<std::string, std::string> kalibrFields(const std::string& camchain, const std::string& cam) {
  std::map<std::string, std::string> fields;
  std::istringstream in(camchain);
  std::string line;
  bool inside = false;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (line[0] != ' ') {
      inside = line == cam + ":";
      continue;
    }
    const size_t colon = line.find(':');
    if (!inside || line.compare(0, 3, "  -") == 0 || colon == std::string::npos) continue;
    const size_t first = line.find_first_not_of(' ');
    const std::string value = colon + 1 < line.size() ? line.substr(line.find_first_not_of(' ', colon + 1)) : "";
    if (!value.empty()) fields[line.substr(first, colon - first)] = value;
  }
  return fields;
}

// EuRoC's sensor.yaml of one camera; body frame = camera 0, T_BS = T_cam0_camN.
std::string sensorYaml(const std::string& camchain, int index, const Matrix3d& R_body_cam, const Vector3d& t_body_cam,
                       double fps) {
  const std::string cam = "cam" + std::to_string(index);
  std::map<std::string, std::string> k = kalibrFields(camchain, cam);
  std::string data;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      const double v = r == 3 ? (c == 3 ? 1.0 : 0.0) : c == 3 ? t_body_cam(r) : R_body_cam(r, c);
      data += (data.empty() ? "" : ", ") + num(v);
    }
  std::string s = "# " + cam + ": synthetic fisheye (curvestereo synth --sequence). Body frame = cam0.\n";
  s += "sensor_type: camera\ncomment: " + cam + "\nT_BS:\n  cols: 4\n  rows: 4\n  data: [" + data + "]\n";
  s += "rate_hz: " + num(fps) + "\nresolution: " + k["resolution"] + "\ncamera_model: " + k["camera_model"] + "\n";
  s += "intrinsics: " + k["intrinsics"] + (k["camera_model"] == "pinhole" ? "  # fu, fv, cu, cv" : "") + "\n";
  s += "distortion_model: " + k["distortion_model"] + "\ndistortion_coefficients: " + k["distortion_coeffs"] + "\n";
  return s;
}

// Fresh sensor noise for every frame, from the model's seed.
uint32_t frameNoiseSeed(uint32_t seed, int frame) {
  Random random(seed ^ (0x9E3779B9u * uint32_t(frame + 1)));
  return random.bits();
}

struct Stream {
  const char* folder;  // under mav0
  const char* extension;
};
const Stream kStreams[] = {{"cam0", ".png"},   {"cam1", ".png"},   {"depth0", ".exr"},
                           {"depth1", ".exr"}, {"mover0", ".png"}, {"mover1", ".png"}};

void measure(const SequenceFrame& f, SequenceFrameReport& r) {
  const ImageF* depth[2] = {&f.pair.depthLeft, &f.pair.depthRight};
  const ImageF* mask[2] = {&f.moverLeft, &f.moverRight};
  double nearest = std::numeric_limits<double>::infinity(), moverNear = nearest, moverFar = 0.0;
  for (int c = 0; c < 2; ++c) {
    long valid = 0, moving = 0;
    for (size_t i = 0; i < depth[c]->size(); ++i) {
      const float d = depth[c]->data[i];
      if (!(d > 0.f)) continue;
      ++valid;
      if (c == 0) nearest = std::min(nearest, double(d));
      if (mask[c]->empty() || mask[c]->data[i] == 0.f) continue;
      ++moving;
      moverNear = std::min(moverNear, double(d));
      moverFar = std::max(moverFar, double(d));
    }
    r.moverShare[c] = valid ? double(moving) / double(valid) : 0.0;
  }
  r.nearest = std::isinf(nearest) ? 0.0 : nearest;
  r.moverNearest = moverFar > 0.0 ? moverNear : 0.0;
  r.moverFarthest = moverFar;
}

std::string metaJson(const SequenceRenderer& renderer, const CameraPhotometry& camera, const SequenceReport& report) {
  const SequenceConfig& cfg = renderer.config();
  const Rig& rig = renderer.rig();
  const Vector3d centre1 = -rig.R.transpose() * rig.t;
  const double rotationDeg = std::acos(std::clamp(0.5 * (rig.R.trace() - 1.0), -1.0, 1.0)) * 180.0 / M_PI;
  const Pose &first = renderer.pose0(0), &last = renderer.pose0(cfg.frames - 1);
  std::ostringstream j;
  j << "{\n \"kind\": \"sequence\",\n \"generator\": \"curvestereo synth --sequence\",\n";
  j << " \"scene_type\": \"" << cfg.render.scene << "\",\n \"seed\": " << cfg.render.seed << ",\n";
  j << " \"frames\": " << cfg.frames << ",\n \"fps\": " << num(cfg.fps) << ",\n";
  j << " \"timestamps_ns\": {\"first\": 1000000000000, \"step\": " << num(1e9 / cfg.fps)
    << ", \"rule\": \"t_ns = 1e12 + round(frame * 1e9 / fps)\"},\n";
  j << " \"motion\": {\"speed_m_per_s\": " << num(cfg.speed) << ", \"turn_deg_per_s\": " << num(cfg.turnDegPerS)
    << ", \"bob_m\": " << num(cfg.bobM) << ", \"bob_hz\": " << num(cfg.bobHz) << "},\n";
  j << " \"motion_definition\": \"frame k at t = k / fps: R(k) = Rz(turn * t) R(0) about the world vertical (turn > "
       "0: left); nominal centre c(k+1) = c(k) + speed / fps * R(k) e_z; the pose's centre is c(k) - bob * sin(2 pi "
       "bob_hz t) * R(k) e_y (up/down bob along the camera's up axis)\",\n";
  j << " \"path_length_m\": " << num(report.pathLength)
    << ",\n \"heading_change_deg\": " << num(report.headingChangeDeg) << ",\n";
  j << " \"cam1_centre_in_cam0_m\": " << vec(centre1) << ",\n \"baseline_m\": " << num(centre1.norm()) << ",\n";
  j << " \"rotation_deg\": " << num(rotationDeg) << ",\n \"T_cn_cnm1\": " << matrix4(rig.R, rig.t) << ",\n";
  j << " \"T_world_cam0_first\": " << matrix4(first.rotation, first.centre) << ",\n";
  j << " \"T_world_cam0_last\": " << matrix4(last.rotation, last.centre) << ",\n";
  j << " \"world_frame\": \"z up, metres, ground at z = 0; camera frames x right, y down, z forward; poses_cam0.csv "
       "holds T_world_cam0 (camera to world); T_world_cam1 = T_world_cam0 inv(T_cn_cnm1)\",\n";
  if (const auto& m = renderer.mover()) {
    j << " \"mover\": {\"shape\": \"box\", \"size_m\": " << vec(2.0 * m->halfSize)
      << ", \"yaw_deg\": " << num(m->yaw * 180.0 / M_PI) << ", \"velocity_m_per_s\": " << vec(m->velocity)
      << ", \"centre_first\": " << vec(m->centreAt(0.0))
      << ", \"centre_last\": " << vec(m->centreAt(renderer.seconds(cfg.frames - 1)))
      << ", \"rests_on\": \"the ground, z = 0\"},\n";
  } else {
    j << " \"mover\": null,\n";
  }
  j << " \"render\": {\"width\": " << rig.cam0.width << ", \"height\": " << rig.cam0.height << ", \"camera\": \""
    << rig.cam0.modelName() << "\", \"samples_per_axis\": " << cfg.render.samplesPerAxis
    << ", \"max_fov_deg\": " << num(cfg.render.maxFovDeg) << ", \"nearest_m\": " << num(cfg.render.nearest)
    << ", \"camera_model\": \"" << camera.profile << "\", \"exposure_scale\": " << num(report.exposureScale) << "},\n";
  j << " \"depth\": \"radial distance (m) from the camera centre to the surface seen through the pixel centre; sky "
       "+inf; outside the image circle 0; the mover included\",\n";
  j << " \"per_frame\": [\n";
  for (size_t i = 0; i < report.perFrame.size(); ++i) {
    const SequenceFrameReport& r = report.perFrame[i];
    j << "  {\"timestamp_ns\": " << r.timestampNs << ", \"nearest_m\": " << num(r.nearest)
      << ", \"mover_share\": " << list({r.moverShare[0], r.moverShare[1]})
      << ", \"mover_depth_m\": " << list({r.moverNearest, r.moverFarthest}) << "}"
      << (i + 1 < report.perFrame.size() ? "," : "") << "\n";
  }
  j << " ]\n}\n";
  return j.str();
}

}  // namespace

SequenceReport writeSequence(const SequenceRenderer& renderer, const CameraPhotometry& camera, const std::string& dir,
                             const SequenceCallbacks& callbacks) {
  camera.validate();
  const SequenceConfig& cfg = renderer.config();
  const fs::path root(dir), mav0 = root / "mav0";
  const int streams = renderer.mover() ? 6 : 4;
  for (int s = 0; s < streams; ++s) fs::create_directories(mav0 / kStreams[s].folder / "data");

  const auto start = std::chrono::steady_clock::now();
  SequenceReport report;
  report.frames = cfg.frames;
  std::string poses = "#timestamp [ns],px,py,pz,qx,qy,qz,qw\n";
  std::vector<int64_t> stamps;
  for (int k = 0; k < cfg.frames; ++k) {
    const auto frameStart = std::chrono::steady_clock::now();
    SequenceFrame f = renderer.render(k, [&](double x) {
      if (callbacks.rendering) callbacks.rendering(k, x);
    });
    CameraPhotometry model = camera;
    model.seed = frameNoiseSeed(camera.seed, k);
    const double scale = applyPhotometry(model, f.pair, k == 0 ? 0.0 : report.exposureScale);  // depth untouched
    if (k == 0) report.exposureScale = scale;

    const std::string stem = std::to_string(f.timestampNs);
    auto file = [&](int s) { return (mav0 / kStreams[s].folder / "data" / (stem + kStreams[s].extension)).string(); };
    const bool sixteen = camera.enabled() && camera.bits == 16;
    (sixteen ? writePngGray16 : writePngGray)(file(0), f.pair.left);
    (sixteen ? writePngGray16 : writePngGray)(file(1), f.pair.right);
    writeExr(file(2), f.pair.depthLeft);
    writeExr(file(3), f.pair.depthRight);
    if (streams == 6) {
      writePngGray(file(4), f.moverLeft);
      writePngGray(file(5), f.moverRight);
    }
    stamps.push_back(f.timestampNs);

    const Pose& pose = f.pair.pose0;
    Eigen::Quaterniond q(pose.rotation);
    q.normalize();
    if (q.w() < 0.0) q.coeffs() *= -1.0;
    poses += stem + "," + num(pose.centre.x()) + "," + num(pose.centre.y()) + "," + num(pose.centre.z()) + "," +
             num(q.x()) + "," + num(q.y()) + "," + num(q.z()) + "," + num(q.w()) + "\n";
    if (k > 0) report.pathLength += (pose.centre - renderer.pose0(k - 1).centre).norm();

    SequenceFrameReport r;
    r.index = k;
    r.timestampNs = f.timestampNs;
    measure(f, r);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - frameStart).count();
    if (r.moverShare[0] > 0.0) ++report.moverFrames;
    if (r.moverFarthest > 0.0) {
      report.moverNearest = report.moverFarthest > 0.0 ? std::min(report.moverNearest, r.moverNearest) : r.moverNearest;
      report.moverFarthest = std::max(report.moverFarthest, r.moverFarthest);
    }
    report.moverShareMax = std::max({report.moverShareMax, r.moverShare[0], r.moverShare[1]});
    report.perFrame.push_back(r);
    if (callbacks.frameDone) callbacks.frameDone(r);
  }
  report.headingChangeDeg = cfg.turnDegPerS * renderer.seconds(cfg.frames - 1);

  for (int s = 0; s < streams; ++s) {
    std::string csv = "#timestamp [ns],filename\n";
    for (int64_t t : stamps) csv += std::to_string(t) + "," + std::to_string(t) + kStreams[s].extension + "\n";
    writeText(mav0 / kStreams[s].folder / "data.csv", csv);
  }
  writeText(root / "poses_cam0.csv", poses);
  const fs::path camchain = root / "camchain.yaml";
  saveKalibr(renderer.rig(), camchain.string());
  const std::string chain = readText(camchain);
  const Rig& rig = renderer.rig();
  writeText(mav0 / "cam0" / "sensor.yaml", sensorYaml(chain, 0, Matrix3d::Identity(), Vector3d::Zero(), cfg.fps));
  writeText(mav0 / "cam1" / "sensor.yaml",
            sensorYaml(chain, 1, rig.R.transpose(), -rig.R.transpose() * rig.t, cfg.fps));
  if (camera.enabled()) writeText(root / "photometry.json", camera.json(report.exposureScale));
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  writeText(root / "meta.json", metaJson(renderer, camera, report));
  return report;
}

}  // namespace cs::synth

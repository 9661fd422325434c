// Shared by the calibration fuzz targets (calib, basalt, opencv, orbslam3, vins): any input must give a
// Rig that passes validate() or a one-line cs::Error; anything else (another exception,
// a crash, a sanitizer report) is a finding. A rig that loads must also be usable by the
// camera models, and every format must write it and read it back the same.
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>

#include "curvestereo/camera.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/rig.hpp"
#include "fuzz_util.hpp"

namespace cs::fuzz {

inline void requireOneLine(const cs::Error& e) {
  if (std::string(e.what()).find('\n') != std::string::npos) __builtin_trap();
}

// A rig that loads must be usable: the camera models may not misbehave on it.
inline void exerciseCameras(const Rig& rig) {
  for (const Camera* cam : {&rig.cam0, &rig.cam1}) {
    const BuiltCamera built(*cam);
    const double w = cam->width, h = cam->height;
    for (const Vec2<double>& px : {Vec2<double>(0, 0), Vec2<double>(w - 1, h - 1),
                                   Vec2<double>(0.5 * (w - 1), 0.5 * (h - 1)), Vec2<double>(w - 1, 0)}) {
      Vec3<double> ray;
      if (!built.unproject(px, ray)) continue;
      Vec2<double> back;
      Mat23<double> J;
      (void)built.project(ray, back, &J);
    }
    (void)built.maxAngle();
    (void)cam->scaled(0.5);
  }
}

// Differences a write + read may introduce: none for Kalibr and OpenCV (numbers are
// copied), rounding for Basalt (the pose goes through a quaternion; ucm through alpha).
inline double rigDifference(const Rig& a, const Rig& b) {
  if (a.cam0.model != b.cam0.model || a.cam1.model != b.cam1.model) return INFINITY;
  if (a.cam0.params.size() != b.cam0.params.size() || a.cam1.params.size() != b.cam1.params.size()) return INFINITY;
  double d = std::max((a.R - b.R).cwiseAbs().maxCoeff(), (a.t - b.t).cwiseAbs().maxCoeff() / (1e-3 + a.t.norm()));
  for (const auto& [ca, cb] : {std::pair{&a.cam0, &b.cam0}, std::pair{&a.cam1, &b.cam1}})
    for (size_t i = 0; i < ca->params.size(); ++i)
      d = std::max(d, std::abs(ca->params[i] - cb->params[i]) / (1.0 + std::abs(ca->params[i])));
  return d;
}

// A scratch file per process and name (fuzz_util.hpp's scratchPath keeps one name).
inline std::string scratchFile(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::is_directory("/dev/shm") ? std::filesystem::path("/dev/shm")
                                                                              : std::filesystem::temp_directory_path();
  return (dir / ("curvestereo_fuzz_" + std::to_string(getpid()) + "_" + name)).string();
}

// Whether `format` can hold both cameras' models (else its writer must refuse). OpenCV and
// ORB-SLAM3 hold Kannala-Brandt 4 and pinhole radtan (one model, one size for both cameras);
// Basalt all but MEI; VINS-Fusion (camodocal) KB4, radtan, MEI and unified; Kalibr all.
inline bool mayRefuse(const Rig& rig, CalibFormat format) {
  auto any = [&](CameraModel m) { return rig.cam0.model == m || rig.cam1.model == m; };
  switch (format) {
    case CalibFormat::Kalibr:
      return false;
    case CalibFormat::Basalt:
      return any(CameraModel::Mei);
    case CalibFormat::VinsFusion:
      return any(CameraModel::ExtendedUnified) || any(CameraModel::DoubleSphere);
    case CalibFormat::OpenCv:
    case CalibFormat::OrbSlam3:
      return true;
  }
  return true;
}

// Writes rig as `format` to `name` and reads it back; traps when a valid rig cannot be
// written (except a model the format cannot hold) or reads back different.
inline void roundTrip(const Rig& rig, CalibFormat format, const std::string& name, double tolerance) {
  const std::string path = scratchFile(name);
  try {
    saveCalibration(rig, path, format);
  } catch (const cs::Error& e) {
    requireOneLine(e);
    if (!mayRefuse(rig, format)) __builtin_trap();
    return;
  }
  Rig back;
  try {
    back = loadCalibration(path);
  } catch (const cs::Error&) {
    __builtin_trap();  // a written file must read back
  }
  if (!(rigDifference(rig, back) <= tolerance)) __builtin_trap();
}

// What Basalt's form cannot keep: a quaternion makes R exactly orthonormal (validate()
// allows 1e-6 off), and ucm's alpha = xi / (1 + xi) loses digits as xi grows.
inline double basaltTolerance(const Rig& rig) {
  const double ortho = (rig.R.transpose() * rig.R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  double xi = 0;
  for (const Camera* cam : {&rig.cam0, &rig.cam1})
    if (cam->model == CameraModel::Unified) xi = std::max(xi, std::abs(cam->params[4]));
  return 1e-9 * (1 + xi) + 10 * ortho;
}

// parse(text, format) returns the rig and sets the format it read.
template <class Parse>
int fuzzCalibration(const uint8_t* data, size_t size, Parse parse) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  Rig rig;
  CalibFormat own = CalibFormat::Kalibr;
  try {
    rig = parse(text, own);
  } catch (const cs::Error& e) {
    requireOneLine(e);
    return 0;
  }
  exerciseCameras(rig);
  roundTrip(rig, CalibFormat::Kalibr, "camchain.yaml", 0.0);
  roundTrip(rig, CalibFormat::Basalt, "calibration.json", basaltTolerance(rig));
  roundTrip(rig, CalibFormat::OpenCv, own == CalibFormat::OpenCv ? "stereo.yml" : "stereo.xml", 0.0);
  // A transform's inverse on the way out and back in: rounding of the pose.
  roundTrip(rig, CalibFormat::OrbSlam3, "orbslam3.yaml", basaltTolerance(rig));
  roundTrip(rig, CalibFormat::VinsFusion, "vins.yaml", basaltTolerance(rig));
  return 0;
}

}  // namespace cs::fuzz

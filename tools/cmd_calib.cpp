// curvestereo calib convert IN OUT [--format kalibr|basalt|opencv|orbslam3|vins] [--image-size WxH]
// curvestereo calib show IN [--image-size WxH]
// Calibration files between Kalibr, Basalt, OpenCV, ORB-SLAM3 and VINS-Fusion; the input's
// format is read from its keys, the output's from --format or from OUT's name.
#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/camera_rig.hpp"
#include "curvestereo/rig.hpp"
#include "rig_cli.hpp"

namespace cs::cli {

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

CalibFormat parseFormat(const std::string& name) {
  const std::string n = lower(name);
  if (n == "kalibr") return CalibFormat::Kalibr;
  if (n == "basalt") return CalibFormat::Basalt;
  if (n == "opencv") return CalibFormat::OpenCv;
  if (n == "orbslam3") return CalibFormat::OrbSlam3;
  if (n == "vins") return CalibFormat::VinsFusion;
  throw Error("--format must be kalibr, basalt, opencv, orbslam3 or vins, got '" + name + "'");
}

// .json is Basalt's; Kalibr's names camchain.yaml, <bag>-camchain.yaml and
// <bag>-camchain-imucam.yaml are Kalibr's; .xml is OpenCV's. Any other .yaml / .yml could
// be any of the YAML formats, so the user must say.
CalibFormat formatFromName(const std::string& path) {
  const std::filesystem::path p(path);
  const std::string ext = lower(p.extension().string());
  const std::string stem = lower(p.stem().string());
  if (ext == ".json") return CalibFormat::Basalt;
  if (ext == ".xml") return CalibFormat::OpenCv;
  const bool kalibrName = stem.rfind("camchain", 0) == 0 || stem.find("-camchain") != std::string::npos ||
                          stem.find("_camchain") != std::string::npos;
  if ((ext == ".yaml" || ext == ".yml") && kalibrName) return CalibFormat::Kalibr;
  throw Error("cannot tell the output format from the name '" + path +
              "' (.json = basalt, camchain*.yaml or *-camchain[-imucam].yaml = kalibr, .xml = opencv): pass --format "
              "kalibr|basalt|opencv|orbslam3|vins");
}

std::string describe(const Camera& cam) {
  std::string params;
  for (double p : cam.params) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%s%.10g", params.empty() ? "" : " ", p);
    params += buf;
  }
  return cam.modelName() + " " + std::to_string(cam.width) + "x" + std::to_string(cam.height) + " [" + params + "]";
}

int convert(const Args& args) {
  if (args.positional().size() != 3)
    throw UsageError("calib convert needs IN and OUT: calib convert IN OUT [--format F]");
  const std::string in = args.positional()[1], out = args.positional()[2];
  const CalibFormat to = args.has("format") ? parseFormat(args.get("format", "")) : formatFromName(out);
  CalibFormat from{};
  const Rig rig = loadCalibration(in, &from, calibHintsFromArgs(args));
  if (std::filesystem::exists(out) && std::filesystem::equivalent(in, out))
    throw Error("calib convert: IN and OUT are the same file ('" + out + "')");
  saveCalibration(rig, out, to);
  std::printf("%s (%s) -> %s (%s)\n", in.c_str(), calibFormatName(from), out.c_str(), calibFormatName(to));
  return 0;
}

// A file of more than two cameras: every camera's place on the body, each pair's overlap and
// the pairs run would solve.
void showRig(const CameraRig& rig) {
  if (rig.size() <= 2) return;
  std::printf("rig of %d cameras (cam0 and cam1 above are its first pair); body frame: %s\n", rig.size(),
              rig.poses[0].p.norm() == 0 && rig.poses[0].R.isIdentity() ? "cam0's" : "the IMU's");
  for (int k = 2; k < rig.size(); ++k) std::printf("cam%d: %s\n", k, describe(rig.cameras[size_t(k)]).c_str());
  for (int k = 0; k < rig.size(); ++k) {
    const BodyPose& p = rig.poses[size_t(k)];
    const Eigen::Vector3d axis = p.R.col(2);
    std::printf("cam%d: centre [%.4f, %.4f, %.4f] m, optical axis [%.3f, %.3f, %.3f], view %.1f deg\n", k, p.p.x(),
                p.p.y(), p.p.z(), axis.x(), axis.y(), axis.z(),
                2.0 * viewHalfAngle(rig.cameras[size_t(k)]) * 180.0 / M_PI);
  }
  std::printf("overlap (share of camera i's view that camera j sees, at 1 m, 5 m and infinity):\n");
  for (const PairInfo& p : pairTable(rig))
    std::printf("  cam%d-cam%d: %5.1f %% / %5.1f %%, baseline %.4f m%s\n", p.i, p.j, 100.0 * p.overlapIJ,
                100.0 * p.overlapJI, p.baseline, std::min(p.overlapIJ, p.overlapJI) < kMinOverlap ? " (no pair)" : "");
  std::printf("pairs run solves (--partners 2): %s\n", describePairs(choosePairs(rig)).c_str());
}

int show(const Args& args) {
  if (args.positional().size() != 2) throw UsageError("calib show needs one file: calib show IN");
  CalibFormat format{};
  const Rig rig = loadCalibration(args.positional()[1], &format, calibHintsFromArgs(args));
  // Read before anything is printed, so that a broken rig is its one line alone.
  const bool rigFormat = format == CalibFormat::Kalibr || format == CalibFormat::Basalt;
  const CameraRig cameraRig = rigFormat ? loadCameraRig(args.positional()[1]) : rigFromPair(rig);
  const Eigen::AngleAxisd turn(rig.R);
  std::printf("format: %s\ncam0: %s\ncam1: %s\n", calibFormatName(format), describe(rig.cam0).c_str(),
              describe(rig.cam1).c_str());
  std::printf("X1 = R X0 + t: t = [%.9g, %.9g, %.9g] m (baseline %.6g m), R turns %.6g deg\n", rig.t.x(), rig.t.y(),
              rig.t.z(), rig.t.norm(), turn.angle() * 180.0 / M_PI);
  for (int r = 0; r < 3; ++r)
    std::printf("  [%12.9f %12.9f %12.9f | %12.9f]\n", rig.R(r, 0), rig.R(r, 1), rig.R(r, 2), rig.t(r));
  showRig(cameraRig);
  return 0;
}

}  // namespace

int cmdCalib(const Args& args) {
  args.allowOnly({"format", "image-size"});
  const std::string sub = args.positional().empty() ? "" : args.positional()[0];
  if (sub == "convert") return convert(args);
  if (sub == "show") {
    if (args.has("format")) throw UsageError("calib show takes no --format (the file's content says it)");
    return show(args);
  }
  throw UsageError(
      "calib needs a sub-command: calib convert IN OUT [--format kalibr|basalt|opencv|orbslam3|vins] "
      "[--image-size WxH] | calib show IN [--image-size WxH]");
}

}  // namespace cs::cli

// curvestereo: dense depth from a calibrated fisheye stereo pair, without rectification.
#include <cstdio>
#include <cstring>
#include <exception>
#include <set>
#include <string>

#include "commands.hpp"
#include "common.hpp"

namespace {

const char* kUsage = R"(usage: curvestereo <command> [options]

commands:
  demo [-o OUTDIR] [--size 480] [--scene urban|indoor] [--seed N] [--camera none|t265]
                                render a synthetic fisheye pair, solve it, report accuracy
  run --calib CALIB LEFT RIGHT -o OUTDIR [--scale-intrinsics] [--pinhole FOV[,WxH]] [--equirect W]
                                depth.exr depth.png disparity.exr flow.flo points.ply points.pcd;
                                CALIB: Kalibr / OpenVINS camchain, Basalt calibration.json,
                                OpenCV FileStorage, ORB-SLAM3 settings or VINS-Fusion config
                                (docs/calibration.md); --pinhole: depth_pinhole.exr/.png + camera_info.yaml;
                                --equirect: range_equirect.exr (--sampling nearest|bilinear);
                                --scale-intrinsics: images at a uniform rescale of the
                                calibrated resolution (e.g. half) scale the cameras
  run --sequence SRC -o OUTDIR [--calib CALIB] [--poses FILE] [--cold]
                                a recorded sequence, frame after frame: each frame's outputs
                                in OUTDIR/<t_ns>/; SRC: an ASL/EuRoC folder (mav0/cam0,
                                cam1; its poses_cam0.csv and camchain.yaml are used) or
                                "LEFT,RIGHT" folders or globs paired by sorted name;
                                --poses: T_world_cam0 as CSV (t_ns,px,py,pz,qx,qy,qz,qw)
                                or TUM text; --cold: every frame solved alone (no warm
                                start, no temporal filter)
  eval PAIRDIR... --csv FILE [--md FILE] [--maps DIR] [--sparsification FILE]
                                accuracy against ground truth (tau>1, tau>3, EPE, abs-rel);
                                --sparsification: tau>1 of the most confident 100..50 %
                                beside the oracle's, as CSV and FILE's .png
  eval --sequence DIR... [--cold | --compare] [--blind] [--frames N] [--csv FILE] [--md FILE]
                                a sequence with ground truth (synth --sequence's layout):
                                tau per frame, on the moving object, and flicker; --compare
                                runs cold then warm and prints the ratios; --blind: the
                                solver gets no poses (a camera without odometry)
  bench [--calib CAMCHAIN LEFT RIGHT | --size WxH] [--runs N]
                                time per frame and per stage
  fields --calib CAMCHAIN -o OUTDIR
                                valid mask, calibration and trajectory fields
  calib convert IN OUT [--format kalibr|basalt|opencv|orbslam3|vins] [--image-size WxH]
  calib show IN [--image-size WxH]
                                calibration files between Kalibr, Basalt, OpenCV, ORB-SLAM3
                                and VINS-Fusion; --image-size for files without one
  synth -o OUTDIR [--scene urban|indoor] [--motion binocular|forward|sideways] [--camera none|t265]
                                render a synthetic pair with exact ground truth
  synth --sequence -o OUTDIR [--frames 12] [--fps 30] [--speed 1] [--turn 20] [--mover on|off]
                                render a walking rig's stereo sequence (ASL layout) with
                                ground-truth depth, poses and a moving object's masks

)";

const char* kUsageTail = R"(camera model (synth, demo; off unless asked; depth untouched; writes photometry.json):
  --camera none|t265  then overrides: --exposure MEDIAN (target median grey, 0 = as rendered)
  --vignette RIM (both; rim/centre in (0,1])  --vignette-left RIM  --vignette-right RIM
  --vignette-mode radius|angle  --gain-left G  --gain-right G  --offset-left O  --offset-right O
  --camera-gamma G (I^(1/G))  --blur SIGMA_PX  --shot S  --read R (noise variance S*I+R^2,
  8-bit grey levels)  --bits 8|16  --noise-seed N (default: the scene's --seed)

'curvestereo <command> --help' repeats this text.
)";

std::string usage() { return kUsage + cs::cli::solverUsage() + kUsageTail; }

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
    std::fputs(usage().c_str(), argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const std::string command = argv[1];
  for (int i = 2; i < argc; ++i)
    if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
      std::fputs(usage().c_str(), stdout);
      return 0;
    }
  try {
    // "-o DIR" is accepted as a short form of --o / --output.
    std::vector<char*> rest;
    std::string dashO = "--o";
    for (int i = 2; i < argc; ++i) rest.push_back(!std::strcmp(argv[i], "-o") ? dashO.data() : argv[i]);
    // Options without a value; --sequence is one for synth only (run and bench take a source).
    std::set<std::string> flags = {"quiet", "scale-intrinsics", "cold", "compare", "blind"};
    if (command == "synth") flags.insert("sequence");
    const cs::cli::Args args(int(rest.size()), rest.data(), flags);
    if (command == "run") return cs::cli::cmdRun(args);
    if (command == "demo") return cs::cli::cmdDemo(args);
    if (command == "synth") return cs::cli::cmdSynth(args);
    if (command == "eval") return cs::cli::cmdEval(args);
    if (command == "fields") return cs::cli::cmdFields(args);
    if (command == "bench") return cs::cli::cmdBench(args);
    if (command == "calib") return cs::cli::cmdCalib(args);
    std::fprintf(stderr, "curvestereo: error: unknown command '%s' (try --help)\n", command.c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "curvestereo: error: %s\n", e.what());
    return 1;
  }
}

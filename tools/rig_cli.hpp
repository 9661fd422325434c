// The rig commands' pieces (cmd_rig.cpp: run with N images; eval_rig.cpp: eval of a rig folder).
#pragma once
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "args.hpp"
#include "curvestereo/camera_rig.hpp"
#include "curvestereo/depth_result.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/rig_stereo.hpp"

namespace cs::cli {

// The options of every rig command (run, eval, bench) beside the solver's: one list, for
// their checks.
inline constexpr std::array<const char*, 6> kRigOptions = {"pairs",       "partners",     "panorama-min-confidence",
                                                           "cross-check", "whole-images", "one-way"};

// run --calib RIG IMG0 ... IMGN-1 -o OUTDIR.
int runRig(const Args& args, const std::string& outDir);
// run --sequence DIR: whether it is a rig's (--rig, or an ASL folder with a cam2/).
bool isRigSequence(const Args& args);
// run --sequence DIR of a rig: every frame through RigStereo::next and the panorama.
int runRigSequence(const Args& args, const std::string& outDir);
// bench --calib RIG IMG0 ... IMGN-1: a rig's frames timed, solves and panorama.
int benchRig(const Args& args);
// eval RIGDIR (a folder with cam<k>.png, depth<k>.exr, camchain.yaml, panorama_range.exr).
int evalRig(const Args& args);
// Whether a folder is a rig folder (cam0.png, cam1.png, ...) rather than a pair's.
bool isRigFolder(const std::string& dir);

// --pairs I-J,... or --partners N (default 2): the pairs to solve.
std::vector<PairInfo> rigPairsFromArgs(const Args& args, const CameraRig& rig);
// The solver options; unless --max-fov is given, the field of view of the widest camera
// (viewHalfAngle), at least the preset's.
Params rigParamsFromArgs(const Args& args, const CameraRig& rig);

// A rig's solver as the options ask: --cross-check T (RigStereo::setCrossCheck) and
// --whole-images (whole images rather than solve windows) and --one-way (each pair solved in
// one direction).
std::unique_ptr<RigStereo> rigStereoFromArgs(const Args& args, const CameraRig& rig, const std::vector<PairInfo>& pairs,
                                             const Params& params);
// --panorama-min-confidence C (0 when absent): the panorama leaves out samples below C.
float panoramaMinConfidence(const Args& args);

// "0-1 (overlap 48 % / 47 %, baseline 0.113 m), ...".
std::string describePairs(const std::vector<PairInfo>& pairs);
// The share of a result's pixels with a depth.
double validShare(const DepthResult& r);

}  // namespace cs::cli

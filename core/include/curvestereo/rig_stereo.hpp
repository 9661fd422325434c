// RigStereo: depth for every camera of a rig, from its pairs, each solved by cs::Stereo in
// both directions, and fused per camera (rig_fusion.hpp). Defined in the top layer (stereo/),
// like Stereo; the backend is Stereo's choice.
//
//   cs::CameraRig rig = cs::loadCameraRig("camchain.yaml");
//   cs::RigStereo stereo(rig, cs::choosePairs(rig));
//   cs::RigResult r = stereo.compute(images);   // r.cameras[k]: camera k's depth
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "curvestereo/camera_rig.hpp"
#include "curvestereo/depth_result.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/pose.hpp"
#include "curvestereo/rig_fusion.hpp"

namespace cs {

class Stereo;

// The parameters for a rig's solves: a lens wider than 180 degrees shows its whole image
// circle, so the field of view is widened to the widest camera's (viewHalfAngle) where
// `params` asks for less. The CLI and the Python module apply it unless the user set the
// field of view.
Params rigParams(const CameraRig& rig, Params params);

struct RigResult {
  std::vector<DepthResult> cameras;  // per camera, radial depth from that camera (setCameraOutputs)
  // Per solve (as `solves`), its estimate on its window of the reference's image, after the
  // cross-check: the views a PanoramaFusion over RigStereo::views() takes. Each frame hands
  // these buffers back and forth with the solver (swapped, not copied).
  std::vector<DepthResult> views;
  Panorama panorama;      // RigStereo::setPanorama; empty without it
  double panoramaMs = 0;  // of totalMs, the panorama's part after the solves
  struct Solve {
    int reference = 0, other = 0;  // the pair's cameras: depth for `reference`
    ImageWindow window;            // the part of the reference's image solved (setSolveWindows)
    double ms = 0;
    long long crossCheckInvalidated = 0;  // pixels the cross-check took away (setCrossCheck)
    bool warm = false, redone = false;    // next(): as the direction's DepthResult says
  };
  std::vector<Solve> solves;
  double totalMs = 0;   // the solves, the panorama and the per-camera fusion
  double fusionMs = 0;  // of which what follows the solves: the cross-check, the panorama's rest, the fusion
};

class RigStereo {
 public:
  // Each pair is solved both ways (reference i against j, and j against i; setOneWay), so
  // each camera of a pair gets a depth from it, each on the window of the reference's image
  // that the other camera sees (setSolveWindows). Throws cs::Error as Stereo's constructor
  // does, or when a camera of the rig is in no pair.
  // solveWindows: as setSolveWindows, from the start.
  RigStereo(const CameraRig& rig, const std::vector<PairInfo>& pairs, const Params& params = preset("realtime"),
            const std::string& backend = "auto", bool solveWindows = true);
  ~RigStereo();
  RigStereo(const RigStereo&) = delete;
  RigStereo& operator=(const RigStereo&) = delete;

  // images[k] is camera k's (float grey in [0, 1], its camera's size).
  RigResult compute(const std::vector<ImageF>& images);
  // The same into `out`, whose images are reused from frame to frame (a real-time loop).
  void compute(const std::vector<ImageF>& images, RigResult& out);
  // A frame of a sequence: every direction is its own Stereo sequence (Stereo::next: warm
  // start, temporal filter, the cold schedule and check), so each camera's depth is as
  // steady as a pair's. bodyPose (optional): the rig's pose in the world, T_world_body;
  // each direction's reference camera then moves by its own pose in the world
  // (T_world_body * the camera's BodyPose). compute() between frames does not disturb them.
  RigResult next(const std::vector<ImageF>& images, const Pose* bodyPose = nullptr);
  void next(const std::vector<ImageF>& images, RigResult& out, const Pose* bodyPose = nullptr);
  // The next frame starts a new sequence (cold) in every direction.
  void resetSequence();
  // With a tolerance > 0, each camera's estimate from a pair is checked against the pair's
  // other direction before the fusion (crossCheck in rig_fusion.hpp); 0 (default) leaves it.
  void setCrossCheck(double tolerance);
  // Whether each camera's result carries the disparity and warp of its most confident pair
  // (default: on). Off, the solves return less: a panorama or a point cloud needs neither.
  void setFlowOutputs(bool on);
  // Whether each camera's result carries z and points (default: on). Off, the fusion writes
  // a third less: a panorama needs neither.
  void setPointOutputs(bool on);
  // Whether each direction solves only the window of its reference's image that its partner
  // can see (solvableWindow, grown by kWindowMargin px; default: on) or the whole image. Two
  // fisheyes 90 degrees apart share about half of each image: the window halves the solve.
  // The pixels outside it have no estimate either way; inside, the results differ only by
  // where the pyramid's coarse levels meet the window's edge, and by the levels themselves:
  // a window narrower than the image may have one level fewer (Params::minWidth). Changing
  // it builds the directions' solvers again (and starts a new sequence).
  void setSolveWindows(bool on);
  static constexpr int kWindowMargin = 16;
  // Whether each pair is solved in one direction only (default: off, both). A point that two
  // cameras see then has one estimate rather than two: half the solves, for a panorama that
  // needs each point once. Each camera's own result is its solves' where it has them, and
  // elsewhere its partners' carried into it (completeFromPartner: depth, z, points and
  // confidence; no disparity or warp there). The direction of each pair is the one that
  // keeps the solves shared most evenly among the cameras (on a ring, each camera solves
  // against its next). Changing it builds the directions' solvers again. Throws cs::Error
  // where a cross-check is set (setCrossCheck needs both directions), as setCrossCheck does
  // one way.
  void setOneWay(bool on);
  // Whether compute() and next() fuse each camera's result (RigResult::cameras; default:
  // on). Off, only RigResult::views: a panorama fused from the views needs no more.
  void setCameraOutputs(bool on);
  // Each solve as a panorama view (its reference camera and window), in RigResult::views'
  // order: PanoramaFusion(rig, frame, width, views(), rays()) fuses RigResult::views.
  std::vector<PanoramaView> views() const;
  // With a width > 0, compute() and next() also fuse the panorama (RigResult::panorama): a
  // PanoramaFusion over views() on the solves' backend, each solve's view placed as soon as
  // it ends (with a cross-check, after it), so that its upload and placing overlap the
  // solves still running. minConfidence: as PanoramaFusion::fuse's. 0 (default): no
  // panorama. Throws cs::Error as PanoramaFusion's constructor does.
  void setPanorama(int width, const PanoramaFrame& frame, float minConfidence = 0.f);
  // Whether the directions solve concurrently, one thread each (default: on). The results
  // are the same either way; off, they run one after the other on the calling thread.
  void setConcurrentSolves(bool on);
  // The backend the solves run on, as Stereo names it.
  std::string backendName() const;
  // Each camera's cameraRays(), computed at construction for the fusion: a PanoramaFusion of
  // the same rig can take them rather than computing them again.
  const std::vector<CameraRays>& rays() const { return rays_; }

 private:
  struct Direction {
    int reference, other;
    ImageWindow window;  // of the reference's image
    std::unique_ptr<Stereo> stereo;
    ImageF windowImage;  // the reference's image in the window, reused frame after frame
  };
  void buildDirections();
  Rig windowPair(size_t d, size_t back) const;
  const ImageF& referenceImage(Direction& dir, const std::vector<ImageF>& images);
  template <class Solve>
  void solveAll(const std::vector<ImageF>& images, RigResult& out, Solve&& solve);
  void applyOutputs();
  void fuseCamera(int k, DepthResult& out) const;
  void invalidCamera(const Camera& cam, DepthResult& out) const;
  template <class Solve>
  void solveDirections(Solve& solve, const std::vector<ImageF>& images);  // into estimates_

  CameraRig rig_;
  std::vector<PairInfo> pairs_;
  Params params_;
  std::string backend_;
  bool windows_ = true;
  std::vector<Direction> directions_;
  std::vector<CameraRays> rays_;        // per camera, for the fusion
  std::vector<DepthResult> estimates_;  // per direction, reused frame after frame
  double crossCheck_ = 0;
  bool concurrent_ = true, flow_ = true, points_ = true, oneWay_ = false, cameraOutputs_ = true;
  std::unique_ptr<PanoramaFusion> panorama_;  // setPanorama
  int panoramaWidth_ = 0;
  PanoramaFrame panoramaFrame_;
  float panoramaMinConfidence_ = 0.f;
};

}  // namespace cs

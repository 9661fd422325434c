// Planning and rendering of synthetic stereo sequences (sequence.hpp): the walk of the
// rig, the path of the moving object, and one frame's render with its mover masks.
#include "synth/sequence.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "synth/random.hpp"

namespace cs::synth {
namespace {

using Eigen::Vector3d;

constexpr double kFirstTimestampNs = 1e12;
constexpr double kCameraClearance = 0.15;  // m: no camera centre nearer any static surface
constexpr double kMoverCameraGap = 0.5;    // m: the mover keeps this far from every camera

void checkRange(double v, double lo, double hi, const char* what) {
  if (!(v >= lo && v <= hi)) {
    char text[200];
    std::snprintf(text, sizeof text, "synth: %s must be in %g..%g, got %g", what, lo, hi, v);
    throw Error(text);
  }
}

// Camera 0's pose per frame (the motion of sequence.hpp), from the scene's viewpoint.
std::vector<Pose> walk(const Pose& start, const SequenceConfig& cfg) {
  std::vector<Pose> poses;
  poses.reserve(size_t(cfg.frames));
  const double step = cfg.speed / cfg.fps, turn = cfg.turnDegPerS * M_PI / 180.0 / cfg.fps;
  Vector3d centre = start.centre;
  for (int k = 0; k < cfg.frames; ++k) {
    const double t = k / cfg.fps;
    Pose pose;
    pose.rotation = Eigen::AngleAxisd(turn * k, Vector3d::UnitZ()).toRotationMatrix() * start.rotation;
    const double bob = cfg.bobM * std::sin(2.0 * M_PI * cfg.bobHz * t);
    pose.centre = centre - bob * pose.rotation.col(1);  // the camera's up is -y
    poses.push_back(pose);
    centre += step * pose.rotation.col(2);
  }
  return poses;
}

Pose cameraOnePose(const Rig& rig, const Pose& pose0) {
  Pose pose1;
  pose1.rotation = pose0.rotation * rig.R.transpose();
  pose1.centre = pose0.centre + pose0.rotation * (-rig.R.transpose() * rig.t);
  return pose1;
}

// Smallest distance from p to a static surface other than the ground (planes).
double clearanceAboveGround(const Scene& scene, const Vector3d& p) {
  double nearest = std::numeric_limits<double>::infinity();
  for (const Shape& s : scene.shapes())
    if (s.kind != ShapeKind::Plane) nearest = std::min(nearest, signedDistance(s, p));
  return nearest;
}

// Nothing static between the camera centre and the mover's centre (the box's near side).
bool seesMover(const Scene& scene, const Vector3d& centre, const Mover& mover, double seconds) {
  const Vector3d target = mover.centreAt(seconds);
  Ray ray;
  ray.origin = centre;
  ray.dir = (target - centre).normalized();
  Hit hit;
  return !scene.intersect(ray, hit) || hit.distance > (target - centre).norm() - mover.halfSize.norm();
}

class MoverPlanner {
 public:
  MoverPlanner(const Scene& scene, const std::vector<Pose>& poses0, const std::vector<Pose>& poses1,
               const SequenceConfig& cfg)
      : scene_(scene), poses0_(poses0), poses1_(poses1), cfg_(cfg) {}

  // The first candidate path (distances ahead, then the other direction) on which the
  // mover stays clear of the scene and the cameras and is in plain view mid-sequence.
  Mover plan() const {
    // Its own random stream: the scene is drawn as for a pair of the same seed.
    Random random(cfg_.render.seed * 2654435761u + 0x5eedu);
    const double sx = random.uniform(0.3, 0.4), sy = random.uniform(0.3, 0.4), sz = random.uniform(0.3, 0.4);
    const double speed = random.uniform(0.9, 1.1);
    const double side = random.chance(0.5) ? 1.0 : -1.0;
    Mover mover;
    mover.halfSize = 0.5 * Vector3d(sx, sy, sz);
    mover.material = randomMaterial(random, 0.06);

    const int mid = (cfg_.frames - 1) / 2;
    const double tMid = mid / cfg_.fps;
    const Pose& m = poses0_[size_t(mid)];
    Vector3d forward(m.rotation(0, 2), m.rotation(1, 2), 0.0);
    if (forward.norm() < 1e-6) forward = Vector3d(m.rotation(0, 0), m.rotation(1, 0), 0.0).cross(Vector3d::UnitZ());
    forward.normalize();
    const Vector3d left(-forward.y(), forward.x(), 0.0);
    const Vector3d foot(m.centre.x(), m.centre.y(), 0.0);
    for (double ahead : {2.2, 2.5, 1.9, 2.8, 1.7})  // horizontal distance (m) to the box centre
      for (double direction : {side, -side}) {
        mover.velocity = direction * speed * left;
        mover.yaw = std::atan2(mover.velocity.y(), mover.velocity.x());
        mover.start = foot + ahead * forward + Vector3d(0.0, 0.0, mover.halfSize.z()) - tMid * mover.velocity;
        if (fits(mover, mid)) return mover;
      }
    throw Error("synth: found no free path for the moving object in this scene (try another --seed, or --mover off)");
  }

 private:
  const Scene& scene_;
  const std::vector<Pose>& poses0_;
  const std::vector<Pose>& poses1_;
  const SequenceConfig& cfg_;

  bool fits(const Mover& mover, int mid) const {
    const double reach = mover.halfSize.norm() + 0.05;
    for (int k = 0; k < cfg_.frames; ++k) {
      const double t = k / cfg_.fps;
      const Shape shape = mover.shapeAt(t);
      if (clearanceAboveGround(scene_, shape.centre) < reach) return false;
      if (signedDistance(shape, poses0_[size_t(k)].centre) < kMoverCameraGap) return false;
      if (signedDistance(shape, poses1_[size_t(k)].centre) < kMoverCameraGap) return false;
    }
    const double t = mid / cfg_.fps;
    return seesMover(scene_, poses0_[size_t(mid)].centre, mover, t) &&
           seesMover(scene_, poses1_[size_t(mid)].centre, mover, t);
  }
};

ImageF maskOf(const Image<int>& ids, int shape) {
  ImageF mask(ids.width, ids.height, 0.f);
  for (size_t i = 0; i < ids.size(); ++i) mask.data[i] = ids.data[i] == shape ? 1.f : 0.f;
  return mask;
}

}  // namespace

void SequenceConfig::validate() const {
  if (frames < 1 || frames > 100000) throw Error("synth: --frames must be 1..100000, got " + std::to_string(frames));
  checkRange(fps, 1e-3, 1e4, "--fps (frames per second)");
  checkRange(speed, 0.0, 50.0, "--speed (m/s)");
  checkRange(turnDegPerS, -720.0, 720.0, "--turn (deg/s)");
  checkRange(bobM, 0.0, 0.5, "the walking bob (m)");
  checkRange(bobHz, 0.0, 100.0, "the walking bob frequency (Hz)");
  checkSynthConfig(render);
}

Shape Mover::shapeAt(double seconds) const { return makeBox(centreAt(seconds), halfSize, yaw, material, "mover"); }

int64_t sequenceTimestampNs(int frame, double fps) {
  return int64_t(kFirstTimestampNs) + int64_t(std::llround(double(frame) * 1e9 / fps));
}

SequenceRenderer::SequenceRenderer(const SequenceConfig& cfg) : cfg_(cfg) {
  cfg_.validate();
  rig_ = makeRig(cfg_.render);
  const Vector3d centre1 = -rig_.R.transpose() * rig_.t;

  SceneSpec spec;
  spec.kind = cfg_.render.scene;
  spec.seed = cfg_.render.seed;
  spec.nearest = cfg_.render.nearest;
  spec.otherCentresInCam0 = {centre1};
  spec.pixelAngle = std::min(pixelAngle(rig_.cam0), pixelAngle(rig_.cam1));
  // The viewpoint is drawn before anything that depends on the cameras, so a first build
  // gives the start of the walk; the second keeps the clutter clear of every camera
  // position of the walk (as a pair's scene keeps it clear of its two cameras).
  const Pose start = buildScene(spec).viewpoint;
  poses0_ = walk(start, cfg_);
  std::vector<Pose> poses1;
  spec.otherCentresInCam0.clear();
  for (const Pose& p : poses0_) {
    poses1.push_back(cameraOnePose(rig_, p));
    for (const Vector3d& c : {p.centre, poses1.back().centre})
      spec.otherCentresInCam0.push_back(start.rotation.transpose() * (c - start.centre));
  }
  scene_ = buildScene(spec);
  if (scene_.viewpoint.centre != start.centre || scene_.viewpoint.rotation != start.rotation)
    throw Error("synth: internal error: the scene's viewpoint depends on the other cameras");

  for (int k = 0; k < cfg_.frames; ++k)
    for (const Vector3d& c : {poses0_[size_t(k)].centre, poses1[size_t(k)].centre})
      if (scene_.signedDistance(c) < kCameraClearance) {
        char text[240];
        std::snprintf(text, sizeof text,
                      "synth: the walk runs into the scene at frame %d (%.2f m along); use fewer --frames, a lower "
                      "--speed, another --turn or another --seed",
                      k, (c - start.centre).norm());
        throw Error(text);
      }
  if (cfg_.mover) mover_ = MoverPlanner(scene_, poses0_, poses1, cfg_).plan();
}

Pose SequenceRenderer::pose1(int frame) const { return cameraOnePose(rig_, pose0(frame)); }

SequenceFrame SequenceRenderer::render(int frame, const ProgressCallback& progress) const {
  if (frame < 0 || frame >= cfg_.frames)
    throw Error("synth: frame " + std::to_string(frame) + " is outside the sequence's " + std::to_string(cfg_.frames));
  SequenceFrame f;
  f.index = frame;
  f.timestampNs = sequenceTimestampNs(frame, cfg_.fps);
  SynthPair& p = f.pair;
  p.rig = rig_;
  p.scene = scene_;
  int moverId = -1;
  if (mover_) {
    p.scene.add(mover_->shapeAt(seconds(frame)));
    moverId = int(p.scene.shapes().size()) - 1;
  }
  p.pose0 = pose0(frame);
  p.pose1 = pose1(frame);

  RenderOptions options;
  options.samplesPerAxis = cfg_.render.samplesPerAxis;
  options.maxFovDeg = cfg_.render.maxFovDeg;
  auto half = [&](double offset) {
    return [&progress, offset](double x) {
      if (progress) progress(offset + 0.5 * x);
    };
  };
  Image<int> ids0, ids1;
  renderView(p.scene, rig_.cam0, p.pose0, options, p.left, p.depthLeft, half(0.0), mover_ ? &ids0 : nullptr);
  renderView(p.scene, rig_.cam1, p.pose1, options, p.right, p.depthRight, half(0.5), mover_ ? &ids1 : nullptr);
  if (mover_) {
    f.moverLeft = maskOf(ids0, moverId);
    f.moverRight = maskOf(ids1, moverId);
  }
  return f;
}

}  // namespace cs::synth

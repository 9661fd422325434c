// `curvestereo synth`: a CPU ray caster of procedural, richly textured scenes seen
// through any rig's camera models, with exact ground-truth depth.
//
// World frame: z up, metres. Camera poses are camera-to-world (camera axes: x right,
// y down, z forward). Everything a seed generates is deterministic across platforms
// and thread counts.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "curvestereo/camera.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/rig.hpp"
#include "synth/texture.hpp"

namespace cs::synth {

// ---------------------------------------------------------------- geometry

enum class ShapeKind { Plane, Box, Sphere, Cylinder };

struct Shape {
  ShapeKind kind = ShapeKind::Plane;
  std::string name;
  // Plane: a point on it. Box, sphere: the centre. Cylinder (vertical): the centre
  // of its axis.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();        // plane only (unit)
  double extent = std::numeric_limits<double>::infinity();  // plane only: a disc of this radius around centre
  // Box: half extents in its own frame. Sphere: x = radius. Cylinder: x = radius,
  // z = half height.
  Eigen::Vector3d halfSize = Eigen::Vector3d::Ones();
  double cosYaw = 1.0, sinYaw = 0.0;  // box: rotation about the world z axis
  Material material;
};

struct Ray {
  Eigen::Vector3d origin;
  Eigen::Vector3d dir;  // unit: hit distances are then Euclidean distances
};

struct Hit {
  double distance = 0.0;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // outward
  int shape = -1;
};

struct Pose {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // camera-to-world
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();        // camera centre in world
};

// A plane through point; with a finite extent, only the disc of that radius around point.
Shape makePlane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, const Material& m,
                const std::string& name = "plane", double extent = std::numeric_limits<double>::infinity());
Shape makeBox(const Eigen::Vector3d& centre, const Eigen::Vector3d& halfSize, double yawRad, const Material& m,
              const std::string& name = "box");
Shape makeSphere(const Eigen::Vector3d& centre, double radius, const Material& m, const std::string& name = "sphere");
// Vertical cylinder standing on `base` (centre of its bottom cap).
Shape makeCylinder(const Eigen::Vector3d& base, double radius, double height, const Material& m,
                   const std::string& name = "cylinder");

// Signed distance from p to one shape's surface (negative inside; exact for every kind).
double signedDistance(const Shape& shape, const Eigen::Vector3d& p);

class Scene {
 public:
  void add(Shape shape) { shapes_.push_back(std::move(shape)); }

  // The nearest hit with distance > 0; false when the ray escapes to the sky.
  bool intersect(const Ray& ray, Hit& hit) const;
  // Matte brightness of a surface point, in [0.15, 0.9]; independent of the viewer.
  double radiance(const Hit& hit) const;
  double skyRadiance(const Eigen::Vector3d& dir) const { return skyBrightness(dir); }
  // Minimum over shapes of signedDistance (the scene's distance field).
  double signedDistance(const Eigen::Vector3d& p) const;

  // Texture detail: features are kept a few pixels wide for a camera with angular
  // pixel size pixelAngle (rad) standing at anchor. A property of the scene, not of
  // the viewing ray, so brightness stays view independent.
  void setDetail(const Eigen::Vector3d& anchor, double pixelAngle);

  const std::vector<Shape>& shapes() const { return shapes_; }
  Eigen::Vector3d lightDir = Eigen::Vector3d(0.3, -0.4, 0.866).normalized();  // unit, world
  Pose viewpoint;  // where the generator put camera 0 (a rig: the body, SceneSpec::rigCameras)

 private:
  std::vector<Shape> shapes_;
  Eigen::Vector3d detailAnchor_ = Eigen::Vector3d::Zero();
  double pixelAngle_ = 1.0 / 250.0;
};

// ---------------------------------------------------------------- scene generation

struct SceneSpec {
  std::string kind = "urban";  // urban | indoor
  uint32_t seed = 1;
  double nearest = 2.0;  // distance (m) from camera 0 to the nearest object (not walls / floor)
  // Camera centres besides camera 0 (in camera-0 coordinates) that objects must keep clear of.
  std::vector<Eigen::Vector3d> otherCentresInCam0;
  // A rig: every camera's pose (camera-to-body, camera 0 first) in the body frame. The
  // generator's viewpoint is then the body (placed as it places camera 0 otherwise, nearly
  // level) and otherCentresInCam0 is not used. The scene surrounds the rig (urban: the street
  // is closed behind it too, with clutter there) and each camera after camera 0 gets a near
  // object in its own view, nearest to 1.6 x nearest from it (added after the pair scene's
  // content; pair scenes, without rigCameras, are unchanged by it).
  std::vector<Pose> rigCameras;
  double pixelAngle = 1.0 / 250.0;  // see Scene::setDetail
};

// Throws cs::Error for an unknown kind or a non-positive nearest distance.
Scene buildScene(const SceneSpec& spec);

// ---------------------------------------------------------------- rendering

using ProgressCallback = std::function<void(double)>;  // fraction done in [0, 1]

struct RenderOptions {
  int samplesPerAxis = 3;  // supersampling: n x n rays per pixel, box filter over the pixel
  double maxFovDeg = 180;  // full field of view; 0 = the model's own valid region
};

// image: average brightness of the sub-pixel rays (those outside the valid region count
// as black), 0 where the pixel centre is invalid. depth: radial distance of the surface
// hit by the ray through the pixel centre; +inf for sky; 0 where the centre is invalid.
// shapeIds (optional): the index in scene.shapes() of the surface that ray hits, -1 for
// sky and invalid pixels (e.g. to mask one object exactly where the depth shows it).
void renderView(const Scene& scene, const Camera& camera, const Pose& pose, const RenderOptions& options, ImageF& image,
                ImageF& depth, const ProgressCallback& progress = {}, Image<int>* shapeIds = nullptr);

// An equirectangular panorama width x width/2 around pose.centre in pose.rotation's frame,
// pixel (j, i) along rig_fusion.hpp's panoramaRay(j, i, width): image as renderView's (every
// pixel traced), range the distance to the surface hit by the pixel-centre ray (+inf sky).
// Throws cs::Error for a width that is odd or below 4.
void renderPanorama(const Scene& scene, const Pose& pose, int width, int samplesPerAxis, ImageF& image, ImageF& range,
                    const ProgressCallback& progress = {});

// Equidistant Kannala-Brandt (k = 0), size x size, f = size / pi, c = (size - 1) / 2:
// a 180 deg image circle touching the borders, like the dev data set.
Camera defaultFisheye(int size);

struct SynthConfig {
  std::string scene = "urban";  // urban | indoor
  uint32_t seed = 1;
  Camera camera = defaultFisheye(800);  // both cameras (ignored when rig is set)
  std::string motion = "binocular";     // binocular | forward | sideways
  double baseline = 0.12;               // metres
  double rotationDeg = 0;               // camera 1 rotated about camera 0's y axis
  std::optional<Rig> rig;               // use these cameras and this pose instead
  double nearest = 2.0;
  int samplesPerAxis = 3;
  double maxFovDeg = 180;  // 0: the model's own valid region (needed for > 180 deg lenses)
};

struct SynthPair {
  Rig rig;
  ImageF left, right, depthLeft, depthRight;
  Scene scene;
  Pose pose0, pose1;
};

// The rig of a config: cfg.rig if set, else the camera twice with the motion:
//   binocular: camera 1 centre (B, 0, 0); forward: (0.2B, 0, B); sideways: (B, 0, 0.3B)
// in camera-0 coordinates, camera 1's axes rotated by rotationDeg about camera 0's y axis.
Rig makeRig(const SynthConfig& cfg);

// Throws cs::Error (one line) for samples outside 1..16, a non-positive nearest distance
// or baseline, or a field of view outside 0..360 degrees.
void checkSynthConfig(const SynthConfig& cfg);

// Angular size (rad) of one pixel at the camera's principal point (sets texture detail).
double pixelAngle(const Camera& camera);

// Builds the scene and renders both views. progress: left in [0, 0.5], right in [0.5, 1].
SynthPair renderPair(const SynthConfig& cfg, const ProgressCallback& progress = {});

}  // namespace cs::synth

// Ray casting of a scene through a camera model, and the stereo-pair driver.
#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <thread>

#include "curvestereo/camera.hpp"
#include "curvestereo/rig_fusion.hpp"
#include "synth/scene.hpp"

namespace cs::synth {
namespace {

using Eigen::Vector3d;

// Which pixel positions produce rays: the model's valid region, optionally cut to a
// cone of half-angle maxFov/2 around the optical axis. Holds the model value type
// (built once: e.g. Kannala-Brandt precomputes its turning angle).
template <class Model>
class RayGenerator {
 public:
  RayGenerator(const Model& model, const Pose& pose, double maxFovDeg) : model_(model), pose_(pose) {
    // The tiny tolerance keeps pixels exactly on the 180 deg circle (theta = 90 deg in
    // exact arithmetic) inside, as in the dev data.
    minCosine_ = maxFovDeg > 0.0 ? std::cos(0.5 * maxFovDeg * M_PI / 180.0) - 1e-12 : -2.0;
  }

  bool ray(double x, double y, Ray& out) const {
    Vec3<double> local;
    if (!model_.unproject(Vec2<double>(x, y), local) || !local.allFinite()) return false;
    local.normalize();  // hit distances must be Euclidean distances
    if (local.z() < minCosine_) return false;
    out.origin = pose_.centre;
    out.dir = pose_.rotation * local;
    return true;
  }

 private:
  const Model& model_;
  const Pose& pose_;
  double minCosine_;
};

// Brightness seen along a ray; distance (optional) gets the hit distance, +inf for sky,
// and shape (optional) the index of the shape hit, -1 for sky.
double shade(const Scene& scene, const Ray& ray, double* distance = nullptr, int* shape = nullptr) {
  Hit hit;
  const bool surface = scene.intersect(ray, hit);
  if (distance) *distance = surface ? hit.distance : std::numeric_limits<double>::infinity();
  if (shape) *shape = surface ? hit.shape : -1;
  return surface ? scene.radiance(hit) : scene.skyRadiance(ray.dir);
}

// One row: depth from the pixel-centre ray, brightness from an n x n grid of rays placed
// symmetrically in the pixel (box filter), so the image's centre of mass stays exactly
// at the model's pixel centre. Rays outside the valid region contribute black, which
// darkens the rim of a fisheye disc like a real lens does.
template <class Rays>
void renderRow(const Scene& scene, const Rays& rays, int samples, int y, ImageF& image, ImageF& depth,
               Image<int>* shapeIds) {
  const bool centreIsSample = samples % 2 == 1;  // then the centre ray is reused
  const double weight = 1.0 / double(samples * samples);
  for (int x = 0; x < image.width; ++x) {
    Ray centre;
    if (!rays.ray(x, y, centre)) continue;  // image and depth stay 0
    double distance;
    int shape;
    const double centreValue = shade(scene, centre, &distance, &shape);
    depth(x, y) = float(distance);
    if (shapeIds) (*shapeIds)(x, y) = shape;
    double sum = 0.0;
    for (int j = 0; j < samples; ++j)
      for (int i = 0; i < samples; ++i) {
        if (centreIsSample && i == samples / 2 && j == samples / 2) {
          sum += centreValue;
          continue;
        }
        Ray sub;
        const double dx = (i + 0.5) / samples - 0.5, dy = (j + 0.5) / samples - 0.5;
        if (rays.ray(x + dx, y + dy, sub)) sum += shade(scene, sub);
      }
    image(x, y) = float(sum * weight);
  }
}

// Every pixel of an equirectangular panorama (rig_fusion.hpp's panoramaRay: longitude 0
// along the pose's z axis, latitude up towards -y) is a ray from the pose's centre; the
// sub-pixel rays of the columns at the edges wrap round, as the sphere does.
class PanoramaRays {
 public:
  PanoramaRays(const Pose& pose, int width) : pose_(pose), width_(width) {}

  bool ray(double x, double y, Ray& out) const {
    out.origin = pose_.centre;
    out.dir = pose_.rotation * panoramaRay(x, y, width_);
    return true;
  }

 private:
  const Pose& pose_;
  int width_;
};

// Renders a width x height image from any ray source (RayGenerator, PanoramaRays). Rows
// are handed out dynamically, but each row's result depends only on the row, so the images
// are identical for any number of threads. Only the calling thread reports progress.
template <class Rays>
void renderImage(const Scene& scene, const Rays& rays, int width, int height, int samplesPerAxis, ImageF& image,
                 ImageF& depth, const ProgressCallback& progress, Image<int>* shapeIds) {
  const int samples = std::max(1, samplesPerAxis);
  image = ImageF(width, height, 0.f);
  depth = ImageF(width, height, 0.f);
  if (shapeIds) *shapeIds = Image<int>(width, height, -1);
  std::atomic<int> nextRow{0}, rowsDone{0};
  auto work = [&](bool reports) {
    for (int y = nextRow++; y < height; y = nextRow++) {
      renderRow(scene, rays, samples, y, image, depth, shapeIds);
      const int done = ++rowsDone;
      if (reports && progress) progress(double(done) / height);
    }
  };
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> helpers;
  for (unsigned i = 1; i < threads; ++i) helpers.emplace_back(work, false);
  work(true);
  for (auto& t : helpers) t.join();
  if (progress) progress(1.0);
}

Vector3d motionCentre(const SynthConfig& cfg) {
  const double b = cfg.baseline;
  if (cfg.motion == "binocular") return Vector3d(b, 0.0, 0.0);
  if (cfg.motion == "forward") return Vector3d(0.2 * b, 0.0, b);
  if (cfg.motion == "sideways") return Vector3d(b, 0.0, 0.3 * b);
  throw Error("synth: unknown motion '" + cfg.motion + "' (expected binocular, forward or sideways)");
}

}  // namespace

void checkSynthConfig(const SynthConfig& cfg) {
  if (cfg.samplesPerAxis < 1 || cfg.samplesPerAxis > 16)
    throw Error("synth: samples per axis must be in 1..16, got " + std::to_string(cfg.samplesPerAxis));
  if (!(cfg.nearest > 0.0)) throw Error("synth: the nearest object distance must be positive");
  if (!(cfg.maxFovDeg >= 0.0 && cfg.maxFovDeg <= 360.0))
    throw Error("synth: the field of view must be in 0..360 degrees (0: the model's own)");
  if (!cfg.rig && !(cfg.baseline > 0.0)) throw Error("synth: the baseline must be positive");
}

double pixelAngle(const Camera& cam) {
  const double cx = cam.params.at(2), cy = cam.params.at(3);
  const BuiltCamera camera(cam);
  Vec3<double> a, b;
  if (camera.unproject(Vec2<double>(cx - 0.5, cy), a) && camera.unproject(Vec2<double>(cx + 0.5, cy), b))
    return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
  return 1.0 / cam.params.at(0);
}

void renderView(const Scene& scene, const Camera& camera, const Pose& pose, const RenderOptions& options, ImageF& image,
                ImageF& depth, const ProgressCallback& progress, Image<int>* shapeIds) {
  if (camera.width <= 0 || camera.height <= 0) throw Error("synth: the camera has no image size");
  camera.validate();
  const BuiltCamera built(camera);
  std::visit(
      [&](const auto& model) {
        const RayGenerator rays(model, pose, options.maxFovDeg);
        renderImage(scene, rays, camera.width, camera.height, options.samplesPerAxis, image, depth, progress, shapeIds);
      },
      built.model());
}

void renderPanorama(const Scene& scene, const Pose& pose, int width, int samplesPerAxis, ImageF& image, ImageF& range,
                    const ProgressCallback& progress) {
  if (width < 4 || width % 2 != 0) throw Error("synth: a panorama's width must be even and at least 4");
  const PanoramaRays rays(pose, width);
  renderImage(scene, rays, width, width / 2, samplesPerAxis, image, range, progress, nullptr);
}

Camera defaultFisheye(int size) {
  const double f = size / M_PI, c = 0.5 * (size - 1);
  return Camera::kannalaBrandt4(size, size, f, f, c, c);
}

Rig makeRig(const SynthConfig& cfg) {
  if (cfg.rig) return *cfg.rig;
  const Vector3d centre1 = motionCentre(cfg);
  // Camera 1's axes, expressed in camera 0: camera 0's axes turned about its y axis.
  const Eigen::Matrix3d axes1 = Eigen::AngleAxisd(cfg.rotationDeg * M_PI / 180.0, Vector3d::UnitY()).toRotationMatrix();
  Rig rig;
  rig.cam0 = rig.cam1 = cfg.camera;
  rig.R = axes1.transpose();  // X1 = R X0 + t
  rig.t = -rig.R * centre1;   // so that camera 1's centre, -R^T t, is centre1
  return rig;
}

SynthPair renderPair(const SynthConfig& cfg, const ProgressCallback& progress) {
  checkSynthConfig(cfg);
  SynthPair pair;
  pair.rig = makeRig(cfg);
  const Vector3d centre1 = -pair.rig.R.transpose() * pair.rig.t;

  SceneSpec spec;
  spec.kind = cfg.scene;
  spec.seed = cfg.seed;
  spec.nearest = cfg.nearest;
  spec.otherCentresInCam0 = {centre1};
  spec.pixelAngle = std::min(pixelAngle(pair.rig.cam0), pixelAngle(pair.rig.cam1));
  pair.scene = buildScene(spec);

  pair.pose0 = pair.scene.viewpoint;
  pair.pose1.rotation = pair.pose0.rotation * pair.rig.R.transpose();
  pair.pose1.centre = pair.pose0.centre + pair.pose0.rotation * centre1;

  RenderOptions options;
  options.samplesPerAxis = cfg.samplesPerAxis;
  options.maxFovDeg = cfg.maxFovDeg;
  auto half = [&](double offset) {
    return [&progress, offset](double f) {
      if (progress) progress(offset + 0.5 * f);
    };
  };
  renderView(pair.scene, pair.rig.cam0, pair.pose0, options, pair.left, pair.depthLeft, half(0.0));
  renderView(pair.scene, pair.rig.cam1, pair.pose1, options, pair.right, pair.depthRight, half(0.5));
  return pair;
}

}  // namespace cs::synth

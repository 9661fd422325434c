// PanoramaFusion (rig_fusion.hpp): a rig's panorama on a backend. The host uploads each
// camera's depth, confidence and grey level; the kernels place every pixel's footprint in the
// panorama and splat it in three passes (the best confidence, the nearest confident surface,
// the confidence-weighted mean over that surface), and resolve the sums into the panorama.
#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "curvestereo/backend.hpp"
#include "curvestereo/fusion_checks.hpp"
#include "curvestereo/parallel.hpp"
#include "curvestereo/rig_fusion.hpp"

namespace cs {

// One camera's buffers, and its centre in the panorama's frame.
struct PanoramaCamera {
  Buffer rays, radial, confidence, grey, place;
  float centre[3];
};

struct PanoramaFusion::State {
  std::unique_ptr<Backend> backend;
  std::vector<PanoramaCamera> cameras;
  Buffer accum, range, grey, confidence;
  std::vector<float> radial;  // a camera's radial depth, NaN where it is not valid
  float parallaxSlack = 0.f;  // panoramaParallaxSlack of the rig
};

PanoramaFusion::PanoramaFusion(const CameraRig& rig, const PanoramaFrame& frame, int width, const std::string& backend)
    : PanoramaFusion(rig, frame, width, std::vector<CameraRays>{}, backend) {}

PanoramaFusion::PanoramaFusion(const CameraRig& rig, const PanoramaFrame& frame, int width,
                               const std::vector<CameraRays>& given, const std::string& backend)
    : rig_(rig), width_(width), state_(std::make_unique<State>()) {
  if (!given.empty()) {
    bool fits = int(given.size()) == rig.size();
    for (int k = 0; fits && k < rig.size(); ++k) fits = sameSize(given[size_t(k)], rig.cameras[size_t(k)]);
    if (!fits) throw Error("PanoramaFusion: the rays given are not one per camera, each its camera's size");
  }
  if (width < 4 || width % 2 || width > 32768)
    throw Error("panorama width must be even and 4 to 32768 px, got " + std::to_string(width));
  State& s = *state_;
  s.parallaxSlack = float(panoramaParallaxSlack(rig));
  s.backend = createBackend(backend);
  Backend& b = *s.backend;
  for (int k = 0; k < rig.size(); ++k) {
    const BodyPose& pose = rig.poses[size_t(k)];
    const Camera& cam = rig.cameras[size_t(k)];
    // X_pano = Rf^T (R X_cam + p - centre): the rays turned once, for every frame.
    const Eigen::Matrix3d R = frame.R.transpose() * pose.R;
    const CameraRays rays = given.empty() ? cameraRays(cam) : given[size_t(k)];
    std::vector<float> turned(3 * rays.data.size());
    detail::parallelFor(cam.height, [&](int y) {
      for (int x = 0; x < cam.width; ++x) {
        const size_t i = size_t(y) * size_t(cam.width) + size_t(x);
        const Eigen::Vector3f d = (R * rays.data[i].cast<double>()).cast<float>();
        for (int c = 0; c < 3; ++c) turned[3 * i + size_t(c)] = d[c];
      }
    });
    PanoramaCamera c{b.create(cam.width, cam.height, 3),
                     b.create(cam.width, cam.height, 1),
                     b.create(cam.width, cam.height, 1),
                     b.create(cam.width, cam.height, 1),
                     b.create(cam.width, cam.height, kPanoramaPlaceChannels),
                     {}};
    const Eigen::Vector3d centre = frame.R.transpose() * (pose.p - frame.centre);
    for (int i = 0; i < 3; ++i) c.centre[i] = float(centre[i]);
    b.upload(c.rays, turned.data());
    s.cameras.push_back(c);
  }
  s.accum = b.create(width, width / 2, kPanoramaChannels);
  b.fill(s.accum, 0.f);  // panoramaSplat's starting state; panoramaResolve leaves it so
  s.range = b.create(width, width / 2, 1);
  s.grey = b.create(width, width / 2, 1);
  s.confidence = b.create(width, width / 2, 1);
}

PanoramaFusion::~PanoramaFusion() = default;

std::string PanoramaFusion::backendName() const { return state_->backend->name(); }

Panorama PanoramaFusion::fuse(const std::vector<DepthResult>& cameras, const std::vector<ImageF>& images,
                              float minConfidence) {
  Panorama out;
  fuse(cameras, images, out, minConfidence);
  return out;
}

void PanoramaFusion::fuse(const std::vector<DepthResult>& cameras, const std::vector<ImageF>& images, Panorama& out,
                          float minConfidence) {
  if (int(cameras.size()) != rig_.size() || (!images.empty() && int(images.size()) != rig_.size()))
    throw Error("fusePanorama: " + std::to_string(cameras.size()) + " results and " + std::to_string(images.size()) +
                " images for a rig of " + std::to_string(rig_.size()) + " cameras");
  for (int k = 0; k < rig_.size(); ++k) {
    const Camera& cam = rig_.cameras[size_t(k)];
    checkFusionInput(cameras[size_t(k)], cam, false, "fusePanorama");
    if (!images.empty() && !sameSize(images[size_t(k)], cam))
      throw Error("fusePanorama: image " + std::to_string(k) + " is not its camera's size");
  }
  State& s = *state_;
  Backend& b = *s.backend;
  const Buffer none{};
  for (int k = 0; k < rig_.size(); ++k) {
    const DepthResult& r = cameras[size_t(k)];
    PanoramaCamera& c = s.cameras[size_t(k)];
    s.radial.resize(r.depth.radial.data.size());
    detail::parallelFor(r.depth.radial.height, [&](int y) {
      for (size_t i = size_t(y) * size_t(r.depth.radial.width); i < size_t(y + 1) * size_t(r.depth.radial.width); ++i)
        s.radial[i] = r.valid.data[i] ? r.depth.radial.data[i] : std::numeric_limits<float>::quiet_NaN();
    });
    b.upload(c.radial, s.radial.data());
    b.upload(c.confidence, r.confidence.data.data());
    if (!images.empty() && !images[size_t(k)].empty()) b.upload(c.grey, images[size_t(k)].data.data());
    b.panoramaPlace(c.place, c.radial, c.rays,
                    PanoramaParams{width_, {c.centre[0], c.centre[1], c.centre[2]}, 0.f, 0, s.parallaxSlack});
  }
  for (int pass = kPanoramaBest; pass <= kPanoramaSums; ++pass)
    for (int k = 0; k < rig_.size(); ++k) {
      const PanoramaCamera& c = s.cameras[size_t(k)];
      const bool grey = !images.empty() && !images[size_t(k)].empty();
      b.panoramaSplat(s.accum, c.place, c.confidence, grey ? c.grey : none,
                      PanoramaParams{width_, {0.f, 0.f, 0.f}, minConfidence, pass, s.parallaxSlack});
    }
  b.panoramaResolve(s.range, s.grey, s.confidence, s.accum);
  for (ImageF* image : {&out.range, &out.grey, &out.confidence})
    if (image->width != width_ || image->height != width_ / 2) *image = ImageF(width_, width_ / 2);
  b.downloadAll(
      {{s.range, out.range.data.data()}, {s.grey, out.grey.data.data()}, {s.confidence, out.confidence.data.data()}});
}

Panorama fusePanorama(const CameraRig& rig, const std::vector<DepthResult>& cameras, const std::vector<ImageF>& images,
                      const PanoramaFrame& frame, int width, float minConfidence) {
  return PanoramaFusion(rig, frame, width).fuse(cameras, images, minConfidence);
}

}  // namespace cs

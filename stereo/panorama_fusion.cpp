// PanoramaFusion (rig_fusion.hpp): a rig's panorama on a backend. The host uploads each
// camera's depth, confidence and grey level; the kernels place every pixel's footprint in the
// panorama and splat it in three passes (the best confidence, the nearest confident surface,
// the confidence-weighted mean over that surface), and resolve the sums into the panorama.
#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <mutex>

#include "curvestereo/backend.hpp"
#include "curvestereo/fusion_checks.hpp"
#include "curvestereo/parallel.hpp"
#include "curvestereo/rig_fusion.hpp"

namespace cs {

// One view's buffers (a camera's image or a window of it), and its camera's centre in the
// panorama's frame.
struct PanoramaCamera {
  Buffer rays, radial, confidence, grey, place;
  float centre[3];
};

struct PanoramaFusion::State {
  std::unique_ptr<Backend> backend;
  std::vector<PanoramaView> views;
  std::vector<PanoramaCamera> cameras;  // per view
  Buffer accum, range, grey, confidence;
  std::vector<float> radial, image;  // a view's radial depth (NaN where it is not valid) and grey level
  float parallaxSlack = 0.f;         // panoramaParallaxSlack of the rig
  std::vector<uint8_t> placed;       // per view, this frame: 0 not yet, 1 placed, 2 with its grey
  std::mutex busy;                   // placeView from several threads, one at a time
};

namespace {

std::vector<PanoramaView> wholeCameras(const CameraRig& rig) {
  std::vector<PanoramaView> views;
  for (int k = 0; k < rig.size(); ++k) views.push_back({k, {}});
  return views;
}

// The view's window of `camera`'s image, the whole image where it is empty. Throws cs::Error
// for a camera index or a window outside the image.
ImageWindow viewWindow(const CameraRig& rig, const PanoramaView& v) {
  if (v.camera < 0 || v.camera >= rig.size())
    throw Error("PanoramaFusion: a view of camera " + std::to_string(v.camera) + " in a rig of " +
                std::to_string(rig.size()) + " cameras");
  const Camera& cam = rig.cameras[size_t(v.camera)];
  const ImageWindow w = v.window.orWhole(cam);
  if (w.x0 < 0 || w.y0 < 0 || w.x0 + w.width > cam.width || w.y0 + w.height > cam.height)
    throw Error("PanoramaFusion: a view's window does not fit camera " + std::to_string(v.camera) + "'s image");
  return w;
}

}  // namespace

PanoramaFusion::PanoramaFusion(const CameraRig& rig, const PanoramaFrame& frame, int width, const std::string& backend)
    : PanoramaFusion(rig, frame, width, wholeCameras(rig), std::vector<CameraRays>{}, backend) {}

PanoramaFusion::PanoramaFusion(const CameraRig& rig, const PanoramaFrame& frame, int width,
                               const std::vector<CameraRays>& given, const std::string& backend)
    : PanoramaFusion(rig, frame, width, wholeCameras(rig), given, backend) {}

PanoramaFusion::PanoramaFusion(const CameraRig& rig, const PanoramaFrame& frame, int width,
                               const std::vector<PanoramaView>& views, const std::vector<CameraRays>& given,
                               const std::string& backend)
    : rig_(rig), width_(width), state_(std::make_unique<State>()) {
  if (!given.empty()) {
    bool fits = int(given.size()) == rig.size();
    for (int k = 0; fits && k < rig.size(); ++k) fits = sameSize(given[size_t(k)], rig.cameras[size_t(k)]);
    if (!fits) throw Error("PanoramaFusion: the rays given are not one per camera, each its camera's size");
  }
  if (width < 4 || width % 2 || width > 32768)
    throw Error("panorama width must be even and 4 to 32768 px, got " + std::to_string(width));
  if (views.empty()) throw Error("PanoramaFusion: no views");
  State& s = *state_;
  s.parallaxSlack = float(panoramaParallaxSlack(rig));
  s.backend = createBackend(backend);
  Backend& b = *s.backend;
  std::vector<CameraRays> computed(size_t(rig.size()));
  for (const PanoramaView& view : views) {
    const ImageWindow w = viewWindow(rig, view);
    s.views.push_back({view.camera, w});
    const BodyPose& pose = rig.poses[size_t(view.camera)];
    const Camera& cam = rig.cameras[size_t(view.camera)];
    CameraRays& mine = computed[size_t(view.camera)];
    if (given.empty() && mine.empty()) mine = cameraRays(cam);
    const CameraRays& rays = given.empty() ? mine : given[size_t(view.camera)];
    // X_pano = Rf^T (R X_cam + p - centre): the window's rays turned once, for every frame.
    const Eigen::Matrix3d R = frame.R.transpose() * pose.R;
    std::vector<float> turned(3 * size_t(w.width) * size_t(w.height));
    detail::parallelFor(w.height, [&](int y) {
      for (int x = 0; x < w.width; ++x) {
        const size_t i = size_t(y) * size_t(w.width) + size_t(x);
        const Eigen::Vector3f d = (R * rays(w.x0 + x, w.y0 + y).cast<double>()).cast<float>();
        for (int c = 0; c < 3; ++c) turned[3 * i + size_t(c)] = d[c];
      }
    });
    PanoramaCamera c{b.create(w.width, w.height, 3),
                     b.create(w.width, w.height, 1),
                     b.create(w.width, w.height, 1),
                     b.create(w.width, w.height, 1),
                     b.create(w.width, w.height, kPanoramaPlaceChannels),
                     {}};
    const Eigen::Vector3d centre = frame.R.transpose() * (pose.p - frame.centre);
    for (int i = 0; i < 3; ++i) c.centre[i] = float(centre[i]);
    b.upload(c.rays, turned.data());
    s.cameras.push_back(c);
  }
  s.placed.assign(s.views.size(), 0);
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
  std::vector<const DepthResult*> estimates;
  for (const DepthResult& r : cameras) estimates.push_back(&r);
  fuse(estimates, images, out, minConfidence);
}

void PanoramaFusion::fuse(const std::vector<const DepthResult*>& estimates, const std::vector<ImageF>& images,
                          Panorama& out, float minConfidence) {
  State& s = *state_;
  if (estimates.size() != s.views.size() || (!images.empty() && int(images.size()) != rig_.size()))
    throw Error("fusePanorama: " + std::to_string(estimates.size()) + " results and " + std::to_string(images.size()) +
                " images for " + std::to_string(s.views.size()) + " views of a rig of " + std::to_string(rig_.size()) +
                " cameras");
  for (size_t v = 0; v < s.views.size(); ++v) {
    const int camera = s.views[v].camera;
    placeView(v, *estimates[v], images.empty() || images[size_t(camera)].empty() ? nullptr : &images[size_t(camera)]);
  }
  finish(out, minConfidence);
}

void PanoramaFusion::placeView(size_t v, const DepthResult& r, const ImageF* image) {
  State& s = *state_;
  if (v >= s.views.size())
    throw Error("PanoramaFusion: view " + std::to_string(v) + " of " + std::to_string(s.views.size()));
  const ImageWindow& w = s.views[v].window;
  const Camera& cam = rig_.cameras[size_t(s.views[v].camera)];
  checkFusionInput(r, cam.cropped(w.x0, w.y0, w.width, w.height), false, "fusePanorama");
  if (image && !image->empty() && !sameSize(*image, cam))
    throw Error("fusePanorama: image " + std::to_string(s.views[v].camera) + " is not its camera's size");
  if (image && image->empty()) image = nullptr;
  const std::lock_guard<std::mutex> lock(s.busy);
  Backend& b = *s.backend;
  PanoramaCamera& c = s.cameras[v];
  const bool whole = image && w.width == image->width && w.height == image->height;
  const ImageF* window = whole ? nullptr : image;  // a whole image is uploaded as it is: no copy
  s.radial.resize(r.depth.radial.data.size());
  if (window) s.image.resize(r.depth.radial.data.size());
  detail::parallelFor(w.height, [&](int y) {
    for (size_t i = size_t(y) * size_t(w.width); i < size_t(y + 1) * size_t(w.width); ++i)
      s.radial[i] = r.valid.data[i] ? r.depth.radial.data[i] : std::numeric_limits<float>::quiet_NaN();
    if (window) {
      const float* row = &window->data[size_t(w.y0 + y) * size_t(window->width) + size_t(w.x0)];
      std::copy(row, row + w.width, &s.image[size_t(y) * size_t(w.width)]);
    }
  });
  b.upload(c.radial, s.radial.data());
  b.upload(c.confidence, r.confidence.data.data());
  if (image) b.upload(c.grey, whole ? image->data.data() : s.image.data());
  b.panoramaPlace(c.place, c.radial, c.rays,
                  PanoramaParams{width_, {c.centre[0], c.centre[1], c.centre[2]}, 0.f, 0, s.parallaxSlack});
  s.placed[v] = image ? 2 : 1;
}

void PanoramaFusion::finish(Panorama& out, float minConfidence) {
  State& s = *state_;
  const std::lock_guard<std::mutex> lock(s.busy);
  for (size_t v = 0; v < s.views.size(); ++v)
    if (!s.placed[v]) throw Error("PanoramaFusion: view " + std::to_string(v) + " was not placed for this frame");
  Backend& b = *s.backend;
  const Buffer none{};
  for (int pass = kPanoramaBest; pass <= kPanoramaSums; ++pass)
    for (size_t v = 0; v < s.views.size(); ++v) {
      const PanoramaCamera& c = s.cameras[v];
      b.panoramaSplat(s.accum, c.place, c.confidence, s.placed[v] == 2 ? c.grey : none,
                      PanoramaParams{width_, {0.f, 0.f, 0.f}, minConfidence, pass, s.parallaxSlack});
    }
  std::fill(s.placed.begin(), s.placed.end(), uint8_t(0));
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

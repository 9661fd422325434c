// Fusion of a rig's pair results (host code, a stage above the pair pipeline): each camera's
// depth from its pairs, and the equirectangular panorama around the rig.
#pragma once
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "curvestereo/camera_rig.hpp"
#include "curvestereo/depth_result.hpp"
#include "curvestereo/image.hpp"

namespace cs {

// One camera's estimates (each from a pair with that camera as the reference) made one: per
// pixel the most confident estimate wins, and the others within kAgreement of its inverse
// depth are averaged with it, weighted by confidence. Disparity and warp are the winner's
// (they belong to its pair). The confidence is the winner's. `cam` recomputes the points.
// Throws cs::Error for no estimates, or an estimate without every output at the camera's size.
DepthResult fuseCameraEstimates(const Camera& cam, const std::vector<const DepthResult*>& estimates);
constexpr double kAgreement = 0.05;

// A camera's unit rays per pixel (NaN where it does not unproject): what the fusion reads of
// the camera, as costly to compute as a fusion, so worth keeping for a stream of frames.
using CameraRays = Image<Eigen::Vector3f>;
CameraRays cameraRays(const Camera& cam);
// The same fusion into `out` (its images reused when they are the camera's size), with the
// camera's rays given. The estimates need only valid, radial depth and confidence; the
// result has disparity and warp where every estimate has them (empty otherwise), and z and
// points always, from the fused depth.
void fuseCameraEstimates(const Camera& cam, const std::vector<const DepthResult*>& estimates, const CameraRays& rays,
                         DepthResult& out);
// An estimate of a window of the camera's image (RigStereo solves each direction on the part
// of the reference's image its partner can see, solvableWindow): the result is the window's
// size, and the camera's pixels outside it have no estimate from it.
struct PlacedEstimate {
  const DepthResult* result = nullptr;
  ImageWindow window;  // empty: the whole image
};
// The same fusion of estimates of windows (each result the size of its window, else cs::Error).
// withPoints false: no z or points (empty), a third of what the fusion writes.
void fuseCameraEstimates(const Camera& cam, const std::vector<PlacedEstimate>& estimates, const CameraRays& rays,
                         DepthResult& out, bool withPoints = true);

// A camera's pixels that no estimate of its own reaches, completed from a partner's: each
// valid pixel of `from` (camera i's estimate on its window; pair = pairRig(rig, i, j), j the
// camera completed, with raysI camera i's cameraRays) is carried at its depth into camera j
// and written over the 2 x 2 pixels around where it lands, where `open` (one per pixel of
// camera j) is set and `out` holds no nearer depth: `out` is the z-buffer, so that several
// partners, called in turn, leave the nearest of all their points. The pixel takes the
// point's range from camera j, z and point along its own ray (raysJ, camera j's; when `out`
// has them) and the estimate's confidence; disparity and warp, which belong to the
// partner's pair, are NaN. Points at infinity land as their direction, at +inf. `out` must
// hold camera j's valid, radial depth and confidence (cs::Error otherwise). Returns how many
// pixels became valid.
long long completeFromPartner(const Rig& pair, const PlacedEstimate& from, const CameraRays& raysI,
                              const CameraRays& raysJ, const std::vector<uint8_t>& open, DepthResult& out);

// The round trip between a pair's two directions, on the host, at no solve's cost: each pixel
// of `forward` (camera i's depth from the pair with j; pair = pairRig(rig, i, j)) is carried
// at its depth into camera j and compared with `backward` (camera j's depth from i) at the
// nearest pixel (`forward` needs valid, radial depth and confidence; it may lack the other
// outputs). Where both have a depth and their inverse ranges differ by more than
// `tolerance` of the larger (plus 0.005 / m, so that far points compare in parallax), the
// pixel becomes invalid in `forward` (every output NaN). Pixels whose point leaves camera j's
// image or meets no estimate there stay. Returns how many were invalidated. Throws cs::Error
// when a result lacks its outputs at its camera's size.
long long crossCheck(const Rig& pair, DepthResult& forward, const DepthResult& backward, double tolerance);

// The panorama's frame in the body frame: its y axis (down) is the cameras' mean y axis, its
// z axis (longitude 0) camera 0's optical axis made perpendicular to it, its origin `centre`.
struct PanoramaFrame {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // X_body = R X_pano + centre
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
};
PanoramaFrame panoramaFrame(const CameraRig& rig);

// The unit ray of panorama pixel (column j, row i) of a W x W/2 image: longitude -180 deg at
// the left edge to +180 at the right, latitude +90 (up, -y) at the top; column j's centre at
// lon = -pi + 2 pi (j + 0.5) / W, row i's at lat = pi/2 - pi (i + 0.5) / H;
// ray = (cos lat sin lon, -sin lat, cos lat cos lon).
Eigen::Vector3d panoramaRay(double j, double i, int width);
// The inverse: the (fractional) column and row of a direction.
Eigen::Vector2d panoramaPixel(const Eigen::Vector3d& direction, int width);

// How far apart (1/m) two inverse ranges of one surface may lie in the panorama beyond
// kAgreement's share: the parallax of kPanoramaParallaxPx over the rig's baseline (the mean
// distance from each camera to its nearest neighbour), at its cameras' coarsest resolution
// (px per radian at the image centre). A share alone splits a distant wall: at 15 m over 11 cm
// a solve's few tenths of a pixel are a tenth of the range, and of the split estimates the
// nearest would win. 0 for fewer than two cameras or none that unprojects its centre.
constexpr double kPanoramaParallaxPx = 0.5;
double panoramaParallaxSlack(const CameraRig& rig);

struct Panorama {
  ImageF range;       // metres from the centre; +inf at infinity; NaN where no camera gave one
  ImageF grey;        // the images' grey level, [0, 1]; NaN where no range
  ImageF confidence;  // the best confidence among the fused estimates; NaN where no range
};

// Forward-projects every camera's points (per-camera results, cameras[k]'s frame) into the
// panorama, each pixel as a footprint the size of its neighbours' spacing there. Per
// panorama pixel, samples below half the best confidence there are dropped; of the rest, the
// nearest range and those on its surface (within kAgreement of its inverse range, plus
// panoramaParallaxSlack: a z-buffer) are averaged, weighted by confidence. Samples below
// minConfidence are left out altogether (a panorama with fewer holes, or fewer errors: the
// choice is the caller's). width: even, 4 to 32768. Throws cs::Error when a result lacks its
// valid mask, radial depth or confidence at its camera's size, or an image (optional: none
// gives NaN grey) is not that size. Runs on the CPU backend; PanoramaFusion chooses.
Panorama fusePanorama(const CameraRig& rig, const std::vector<DepthResult>& cameras, const std::vector<ImageF>& images,
                      const PanoramaFrame& frame, int width, float minConfidence = 0.f);

// What one estimate splatted into the panorama covers: `window` of camera `camera`'s image
// (empty: the whole image). RigStereo's directions are such views (RigStereo::views).
struct PanoramaView {
  int camera = 0;
  ImageWindow window;
};

// fusePanorama for a stream of frames, on a backend (the splats and their three passes are
// kernels: backend.hpp panoramaPlace, panoramaSplat, panoramaResolve): each camera's rays
// turned and uploaded once, at construction, and the backend's buffers kept from frame to
// frame. fuse() is fusePanorama with this rig, frame and width; on a GPU backend the sums
// are in the device's order, so the values agree with the CPU's to rounding. `backend` is a
// name as Stereo takes it ("cpu", "cuda", "vulkan", "auto"). One thread at a time per
// object. Throws cs::Error for a width that is not even and 4 to 32768, or a backend that
// is not usable.
class PanoramaFusion {
 public:
  PanoramaFusion(const CameraRig& rig, const PanoramaFrame& frame, int width, const std::string& backend = "cpu");
  // The same from each camera's cameraRays() that the caller already has (RigStereo::rays()),
  // rather than computing them again. Throws cs::Error when they are not one per camera, each
  // its camera's size.
  PanoramaFusion(const CameraRig& rig, const PanoramaFrame& frame, int width, const std::vector<CameraRays>& rays,
                 const std::string& backend = "cpu");
  // Estimates of views rather than whole cameras (several may be of one camera: a rig's
  // pair directions, each on its window), splatted as they are: the panorama fuses them by
  // confidence and visibility as it fuses cameras, so a rig need not fuse each camera first.
  // rays: per camera as above, or empty (computed here). Throws cs::Error for no views, or a
  // view whose camera is not the rig's or whose window does not fit its image.
  PanoramaFusion(const CameraRig& rig, const PanoramaFrame& frame, int width, const std::vector<PanoramaView>& views,
                 const std::vector<CameraRays>& rays, const std::string& backend = "cpu");
  ~PanoramaFusion();
  PanoramaFusion(const PanoramaFusion&) = delete;
  PanoramaFusion& operator=(const PanoramaFusion&) = delete;
  Panorama fuse(const std::vector<DepthResult>& cameras, const std::vector<ImageF>& images, float minConfidence = 0.f);
  // The same into `out`, its images reused when they are the panorama's size.
  void fuse(const std::vector<DepthResult>& cameras, const std::vector<ImageF>& images, Panorama& out,
            float minConfidence = 0.f);
  // One estimate per view (each its window's size) and the images per camera (or none).
  void fuse(const std::vector<const DepthResult*>& estimates, const std::vector<ImageF>& images, Panorama& out,
            float minConfidence = 0.f);
  // fuse() in two steps, for a caller whose estimates arrive one by one (RigStereo places
  // each solve's view as it finishes, while the others still solve): every view placed once,
  // in any order, from any thread (one at a time: it locks), then finish(). image: the
  // view's camera's whole image, or none. Throws cs::Error as fuse() does, and from finish()
  // when a view was not placed since the last finish().
  void placeView(size_t view, const DepthResult& estimate, const ImageF* image);
  void finish(Panorama& out, float minConfidence = 0.f);
  int width() const { return width_; }
  std::string backendName() const;

 private:
  struct State;  // the backend and its buffers
  CameraRig rig_;
  int width_;
  std::unique_ptr<State> state_;
};

// Every camera's points in the panorama frame, with their grey level, at least minConfidence.
// Throws cs::Error when the results or images are not one per camera, at its size.
struct RigPoint {
  float x, y, z;
  float grey;
};
std::vector<RigPoint> mergedPoints(const CameraRig& rig, const std::vector<DepthResult>& cameras,
                                   const std::vector<ImageF>& images, const PanoramaFrame& frame,
                                   float minConfidence = 0.f);

}  // namespace cs

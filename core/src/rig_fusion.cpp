// Fusion of a rig's pair results on the host (rig_fusion.hpp): not yet a backend kernel.
#include "curvestereo/rig_fusion.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "curvestereo/parallel.hpp"

namespace cs {

namespace {

constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();

bool agrees(double a, double b) {
  // Inverse depths, so that +inf (0) agrees only with nearly infinite depths.
  const double ia = 1.0 / a, ib = 1.0 / b;
  return std::abs(ia - ib) <= kAgreement * std::max(ia, ib);
}

// Confidence as a weight: never zero, so that a lone estimate of confidence 0 still counts.
double weightOf(float confidence) { return std::isfinite(confidence) ? std::max(double(confidence), 1e-6) : 1e-6; }

// f(begin, end) over [0, n) in contiguous chunks, one per thread of the host's pool (the
// fusion is per pixel and independent, and a rig's frame is millions of them).
template <class F>
void inChunks(int n, F&& f) {
  const int chunks = std::clamp(detail::parallelWorkers(), 1, std::max(1, n));
  detail::parallelFor(chunks, [&](int t) { f(int(1LL * n * t / chunks), int(1LL * n * (t + 1) / chunks)); });
}

}  // namespace

CameraRays cameraRays(const Camera& cam) {
  const BuiltCamera built(cam);
  CameraRays rays(cam.width, cam.height, Eigen::Vector3f::Constant(kNaNf));
  inChunks(cam.height, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < cam.width; ++x) {
        Vec3<double> ray;
        if (built.unproject(Vec2<double>(x, y), ray)) rays(x, y) = ray.cast<float>();
      }
  });
  return rays;
}

namespace {

template <class T>
bool sameSize(const Image<T>& image, const Camera& cam) {
  return image.width == cam.width && image.height == cam.height;
}

// The fusion reads a result's valid mask, radial depth and confidence (and, for a camera's
// fusion, every other output), so each must be the camera's size.
void checkResult(const DepthResult& r, const Camera& cam, bool allOutputs, const char* what) {
  const bool sizes = sameSize(r.valid, cam) && sameSize(r.depth.radial, cam) && sameSize(r.confidence, cam);
  const bool others = !allOutputs || (sameSize(r.disparity, cam) && sameSize(r.warp, cam) && sameSize(r.depth.z, cam) &&
                                      sameSize(r.depth.points, cam));
  if (!sizes || !others)
    throw Error(std::string(what) + ": a result for a camera of " + std::to_string(cam.width) + "x" +
                std::to_string(cam.height) + " px needs " +
                (allOutputs ? "every output" : "valid, depth and confidence") + " at that size (Stereo::setOutputs)");
}

}  // namespace

DepthResult fuseCameraEstimates(const Camera& cam, const std::vector<const DepthResult*>& estimates) {
  if (estimates.empty()) throw Error("fuseCameraEstimates: no estimates");
  for (const DepthResult* e : estimates) checkResult(*e, cam, true, "fuseCameraEstimates");
  DepthResult out;
  fuseCameraEstimates(cam, estimates, cameraRays(cam), out);
  return out;
}

namespace {

template <class T>
void sizeFor(Image<T>& image, const Camera& cam) {
  if (!sameSize(image, cam)) image = Image<T>(cam.width, cam.height);
}

// Every output of pixel p made NaN: DepthResult's contract where valid is 0. Outputs a result
// does not carry (empty) are left.
void invalidate(DepthResult& r, size_t p) {
  r.valid.data[p] = 0;
  r.depth.radial.data[p] = r.confidence.data[p] = kNaNf;
  if (!r.disparity.empty()) r.disparity.data[p] = kNaNf;
  if (!r.depth.z.empty()) r.depth.z.data[p] = kNaNf;
  if (!r.warp.empty()) r.warp.data[p] = {kNaNf, kNaNf};
  if (!r.depth.points.empty()) r.depth.points.data[p] = {kNaNf, kNaNf, kNaNf};
}

// Pixel p of `out` from the estimates: the most confident one, averaged with those that agree.
void fusePixel(const std::vector<const DepthResult*>& estimates, const Eigen::Vector3f& ray, bool withFlow, size_t p,
               DepthResult& out) {
  const DepthResult* best = nullptr;
  for (const DepthResult* e : estimates)
    if (e->valid.data[p] && (!best || weightOf(e->confidence.data[p]) > weightOf(best->confidence.data[p]))) best = e;
  if (!best) return invalidate(out, p);
  const double bestDepth = best->depth.radial.data[p];
  double inverseSum = 0, weightSum = 0;
  for (const DepthResult* e : estimates) {
    const double d = e->depth.radial.data[p];
    if (!e->valid.data[p] || !agrees(d, bestDepth)) continue;
    const double w = weightOf(e->confidence.data[p]);
    inverseSum += w / d, weightSum += w;
  }
  const double depth = 1.0 / (inverseSum / weightSum);
  out.valid.data[p] = 1;
  if (withFlow) out.disparity.data[p] = best->disparity.data[p], out.warp.data[p] = best->warp.data[p];
  out.confidence.data[p] = best->confidence.data[p];
  out.depth.radial.data[p] = float(depth);
  out.depth.z.data[p] = std::isfinite(depth) ? float(depth * ray.z()) : INFINITY;
  out.depth.points.data[p] = std::isfinite(depth)
                                 ? Point3f{float(depth * ray.x()), float(depth * ray.y()), float(depth * ray.z())}
                                 : Point3f{kNaNf, kNaNf, kNaNf};
}

}  // namespace

void fuseCameraEstimates(const Camera& cam, const std::vector<const DepthResult*>& estimates, const CameraRays& rays,
                         DepthResult& out) {
  if (estimates.empty()) throw Error("fuseCameraEstimates: no estimates");
  for (const DepthResult* e : estimates) checkResult(*e, cam, false, "fuseCameraEstimates");
  if (!sameSize(rays, cam)) throw Error("fuseCameraEstimates: the rays are not the camera's size");
  bool withFlow = true;
  for (const DepthResult* e : estimates) withFlow = withFlow && sameSize(e->disparity, cam) && sameSize(e->warp, cam);
  const DepthResult& first = *estimates.front();
  out.stages = first.stages;
  out.totalMs = first.totalMs;
  out.warm = first.warm, out.redone = first.redone;
  out.consistentShare = first.consistentShare, out.meanConfidence = first.meanConfidence;
  out.lrPassShare = first.lrPassShare;
  sizeFor(out.valid, cam), sizeFor(out.confidence, cam), sizeFor(out.depth.radial, cam);
  sizeFor(out.depth.z, cam), sizeFor(out.depth.points, cam);
  if (withFlow) {
    sizeFor(out.disparity, cam), sizeFor(out.warp, cam);
  } else {
    out.disparity = ImageF(), out.warp = FlowImage();
  }
  inChunks(cam.height, [&](int y0, int y1) {
    for (size_t p = size_t(y0) * size_t(cam.width); p < size_t(y1) * size_t(cam.width); ++p)
      fusePixel(estimates, rays.data[p], withFlow, p, out);
  });
}

namespace {

// Inverse ranges within tolerance of the larger, or within the slack that a fraction of a
// pixel of parallax makes of distant points.
bool consistent(double inverseA, double inverseB, double tolerance) {
  constexpr double kInverseSlack = 0.005;
  return std::abs(inverseA - inverseB) <= tolerance * std::max(inverseA, inverseB) + kInverseSlack;
}

}  // namespace

long long crossCheck(const Rig& pair, DepthResult& forward, const DepthResult& backward, double tolerance) {
  checkResult(forward, pair.cam0, false, "crossCheck");
  checkResult(backward, pair.cam1, false, "crossCheck");
  const Image<Eigen::Vector3f> rays = cameraRays(pair.cam0);
  const BuiltCamera other(pair.cam1);
  long long invalidated = 0;
  for (int y = 0; y < forward.valid.height; ++y)
    for (int x = 0; x < forward.valid.width; ++x) {
      const double depth = forward.depth.radial(x, y);
      const Eigen::Vector3d ray = rays(x, y).cast<double>();
      if (!forward.valid(x, y) || !ray.allFinite()) continue;
      // A point at infinity is its direction; in camera j it is at infinity too.
      const Eigen::Vector3d inOther =
          std::isfinite(depth) ? Eigen::Vector3d(pair.R * (depth * ray) + pair.t) : Eigen::Vector3d(pair.R * ray);
      Vec2<double> px;
      if (!other.project(inOther, px) || !other.inImage(px)) continue;
      const int u = int(std::lround(px.x())), v = int(std::lround(px.y()));
      if (u < 0 || v < 0 || u >= backward.valid.width || v >= backward.valid.height || !backward.valid(u, v)) continue;
      const double inverseHere = std::isfinite(depth) ? 1.0 / inOther.norm() : 0.0;
      if (consistent(inverseHere, 1.0 / double(backward.depth.radial(u, v)), tolerance)) continue;
      invalidate(forward, size_t(y) * size_t(forward.valid.width) + size_t(x));
      ++invalidated;
    }
  return invalidated;
}

PanoramaFrame panoramaFrame(const CameraRig& rig) {
  PanoramaFrame f;
  f.centre = rig.centre();
  Eigen::Vector3d down = Eigen::Vector3d::Zero();
  for (const BodyPose& pose : rig.poses) down += pose.R.col(1);
  // Cameras facing up and down cancel their y axes; camera 0's own then says where down is.
  down = down.norm() > 0.5 * double(rig.poses.size()) ? down.normalized() : rig.poses.front().R.col(1);
  Eigen::Vector3d forward = rig.poses.front().R.col(2);
  forward -= forward.dot(down) * down;
  if (forward.norm() < 1e-6) forward = rig.poses.front().R.col(0).cross(down);
  forward.normalize();
  f.R.col(1) = down;
  f.R.col(2) = forward;
  f.R.col(0) = down.cross(forward);
  return f;
}

Eigen::Vector3d panoramaRay(double j, double i, int width) {
  const int height = width / 2;
  const double lon = -M_PI + 2.0 * M_PI * (j + 0.5) / width;
  const double lat = M_PI / 2 - M_PI * (i + 0.5) / height;
  return {std::cos(lat) * std::sin(lon), -std::sin(lat), std::cos(lat) * std::cos(lon)};
}

Eigen::Vector2d panoramaPixel(const Eigen::Vector3d& d, int width) {
  const int height = width / 2;
  const double lon = std::atan2(d.x(), d.z()), lat = std::atan2(-d.y(), std::hypot(d.x(), d.z()));
  return {(lon + M_PI) / (2.0 * M_PI) * width - 0.5, (M_PI / 2 - lat) / M_PI * height - 0.5};
}

namespace {

// A camera pixel's footprint in the panorama: its centre there, its half-width and
// half-height (px) and its range.
struct Splat {
  Eigen::Vector2f at, radius;
  float range, confidence, grey;
};

// The largest half-size of a footprint, in panorama pixels at the equator: larger footprints
// would smear a surface over what lies beside it.
constexpr double kMaxSplatRadius = 3.0;

// The footprint's half-sizes: half the spacing to the neighbours on the same surface, at
// least half a pixel, at most kMaxSplatRadius of the sphere's arc. A column's arc shrinks
// with cos(latitude), so near the poles a camera pixel spans many columns.
Eigen::Vector2f footprint(const Eigen::Vector2f& spacing, double row, int width) {
  const double height = width / 2, latitude = M_PI / 2 - M_PI * (row + 0.5) / height;
  const double columns = kMaxSplatRadius / std::max(std::cos(latitude), 2.0 * kMaxSplatRadius / width);
  return {float(std::clamp(0.5 * spacing.x(), 0.5, columns)),
          float(std::clamp(0.5 * spacing.y(), 0.5, kMaxSplatRadius))};
}

// panoramaPixel in float, for the millions of pixels a rig's frame places: float's 1e-7 of
// a turn is 1e-4 px at 2048 columns, ample for footprints of at least half a pixel.
Eigen::Vector2f panoramaPixelF(const Eigen::Vector3f& d, int width) {
  const float height = float(width / 2), pi = float(M_PI);
  const float lon = std::atan2(d.x(), d.z()), lat = std::atan2(-d.y(), std::sqrt(d.x() * d.x() + d.z() * d.z()));
  return {(lon + pi) / (2.f * pi) * float(width) - 0.5f, (pi / 2.f - lat) / pi * height - 0.5f};
}

// Where one camera's pixels land in the panorama: each pixel's position there (NaN where the
// pixel has no depth or the camera does not unproject it), its footprint's half-sizes and its
// range from the centre.
struct Placement {
  Image<Eigen::Vector2f> at, radius;  // the footprint: centre and half-sizes (Splat)
  ImageF range;
};

// A camera pixel that splats: camera k, pixel index y * width + x.
struct SplatRef {
  int camera, pixel;
};

// Band b of `bands` holds the panorama rows [rowOfBand(b), rowOfBand(b + 1)).
int rowOfBand(int b, int bands, int height) { return int(1LL * height * b / bands); }
int bandOfRow(int row, int bands, int height) {
  int b = int(1LL * row * bands / height);  // at most one off: rowOfBand rounds down
  while (b + 1 < bands && rowOfBand(b + 1, bands, height) <= row) ++b;
  while (b > 0 && rowOfBand(b, bands, height) > row) --b;
  return b;
}

// Three passes over the splats: the best confidence per pixel, the nearest confident range
// (the z-buffer), then the confidence-weighted mean of the samples on that nearest surface.
// Each pass touches only the rows [rowBegin, rowEnd) of a band: the bands' threads share the
// accumulator but no pixel, and a pixel's samples arrive in the same order however the rows
// are banded, so the result does not depend on the number of threads.
class PanoramaAccumulator {
 public:
  explicit PanoramaAccumulator(int width)
      : width_(width),
        height_(width / 2),
        bestConfidence_(width, width / 2),
        nearest_(width, width / 2),
        rangeSum_(width, width / 2),
        greySum_(width, width / 2),
        weightSum_(width, width / 2),
        greyWeight_(width, width / 2) {}

  // Rows [rowBegin, rowEnd) emptied for a new frame.
  void reset(int rowBegin, int rowEnd) {
    const size_t begin = size_t(rowBegin) * size_t(width_), end = size_t(rowEnd) * size_t(width_);
    auto fill = [&](ImageF& image, float value) {
      std::fill(image.data.begin() + std::ptrdiff_t(begin), image.data.begin() + std::ptrdiff_t(end), value);
    };
    fill(bestConfidence_, -1.f), fill(nearest_, INFINITY);
    fill(rangeSum_, 0.f), fill(greySum_, 0.f), fill(weightSum_, 0.f), fill(greyWeight_, 0.f);
  }

  template <class F>
  void cover(const Splat& s, int rowBegin, int rowEnd, F&& f) {
    const int x0 = int(std::ceil(s.at.x() - s.radius.x())), x1 = int(std::floor(s.at.x() + s.radius.x()));
    const int y0 = std::max({0, rowBegin, int(std::ceil(s.at.y() - s.radius.y()))}),
              y1 = std::min({height_ - 1, rowEnd - 1, int(std::floor(s.at.y() + s.radius.y()))});
    const int first = ((x0 % width_) + width_) % width_;  // the column, wrapped round the seam
    for (int y = y0; y <= y1; ++y)
      for (int x = x0, wrapped = first; x <= x1; ++x, wrapped = wrapped + 1 == width_ ? 0 : wrapped + 1)
        f(size_t(y) * size_t(width_) + size_t(wrapped));
  }

  void bestPass(const Splat& s, int rowBegin, int rowEnd) {
    const float confidence = confidenceOf(s);
    cover(s, rowBegin, rowEnd,
          [&](size_t k) { bestConfidence_.data[k] = std::max(bestConfidence_.data[k], confidence); });
  }
  void nearestPass(const Splat& s, int rowBegin, int rowEnd) {
    const float confidence = confidenceOf(s);
    cover(s, rowBegin, rowEnd, [&](size_t k) {
      if (confident(confidence, k)) nearest_.data[k] = std::min(nearest_.data[k], s.range);
    });
  }
  void meanPass(const Splat& s, int rowBegin, int rowEnd) {
    const float confidence = confidenceOf(s), w = float(weightOf(s.confidence));
    // Inverse range, so that +inf samples average to +inf without NaN.
    const float inverse = w / s.range, grey = w * s.grey;
    const bool hasGrey = std::isfinite(s.grey);
    cover(s, rowBegin, rowEnd, [&](size_t k) {
      if (!confident(confidence, k) || !agrees(s.range, nearest_.data[k])) return;
      rangeSum_.data[k] += inverse;
      weightSum_.data[k] += w;
      if (hasGrey) greySum_.data[k] += grey, greyWeight_.data[k] += w;
    });
  }

  // Rows [rowBegin, rowEnd) of the panorama `p` (its images the panorama's size).
  void resolve(int rowBegin, int rowEnd, Panorama& p) const {
    for (size_t k = size_t(rowBegin) * size_t(width_); k < size_t(rowEnd) * size_t(width_); ++k) {
      p.range.data[k] = p.grey.data[k] = p.confidence.data[k] = kNaNf;
      if (!(weightSum_.data[k] > 0)) continue;
      p.range.data[k] = weightSum_.data[k] / rangeSum_.data[k];
      p.confidence.data[k] = bestConfidence_.data[k];
      if (greyWeight_.data[k] > 0) p.grey.data[k] = greySum_.data[k] / greyWeight_.data[k];
    }
  }

 private:
  int width_, height_;
  ImageF bestConfidence_, nearest_, rangeSum_, greySum_, weightSum_, greyWeight_;

  static float confidenceOf(const Splat& s) { return std::isfinite(s.confidence) ? s.confidence : 0.f; }
  // A sample well below the best one there is a likely mismatch: it must not hide the surface.
  bool confident(float confidence, size_t k) const { return confidence >= 0.5f * bestConfidence_.data[k]; }
};

}  // namespace

// A camera as the panorama sees it: its rays and its pose in the panorama's frame.
struct PanoramaFusion::CameraView {
  Image<Eigen::Vector3f> rays;        // the camera's, in its frame
  Image<Eigen::Vector3f> turnedRays;  // R rays: the same in the panorama's frame
  Eigen::Vector3f p;                  // X_pano = R X_cam + p

  // The point in the panorama frame; a point at infinity is seen along its direction from
  // anywhere, so it is that direction.
  Eigen::Vector3f pointOf(int x, int y, float range) const {
    return std::isfinite(range) ? Eigen::Vector3f(range * turnedRays(x, y) + p) : turnedRays(x, y);
  }

  // Camera row y of `out`.
  void placeRow(const DepthResult& r, int width, int y, Placement& out) const {
    for (int x = 0; x < r.valid.width; ++x) {
      out.at(x, y) = Eigen::Vector2f::Constant(kNaNf);
      if (!r.valid(x, y) || !rays(x, y).allFinite()) continue;
      const float radial = r.depth.radial(x, y);
      const Eigen::Vector3f point = pointOf(x, y, radial);
      out.at(x, y) = panoramaPixelF(point, width);
      out.range(x, y) = std::isfinite(radial) ? point.norm() : INFINITY;
    }
  }

  // The half-sizes of pixel (x, y)'s footprint, whose position is finite. The steps to the neighbours on
  // the same surface along the camera's rows (a) and columns (b) set it: a box of half-size
  // (|a| + |b|) / 2 per axis covers the cell they span however the camera's grid lies in the
  // panorama, so the panorama has no holes where it samples more finely than the camera.
  Eigen::Vector2f radiusOf(const Placement& placed, const DepthResult& r, int x, int y, int width) const {
    const ImageF& radial = r.depth.radial;
    const Eigen::Vector2f at = placed.at(x, y);
    Eigen::Vector2f a = Eigen::Vector2f::Zero(), b = Eigen::Vector2f::Zero();
    for (const auto& [nx, ny] : {std::pair{x + 1, y}, std::pair{x, y + 1}, std::pair{x - 1, y}, std::pair{x, y - 1}}) {
      if (nx < 0 || ny < 0 || nx >= radial.width || ny >= radial.height || !r.valid(nx, ny)) continue;
      if (!agrees(radial(nx, ny), radial(x, y)) || !rays(nx, ny).allFinite()) continue;
      Eigen::Vector2f step = placed.at(nx, ny) - at;
      // Across the longitude seam (remainder is exact, and the identity within half a turn).
      if (std::abs(step.x()) > 0.5f * float(width)) step.x() = std::remainder(step.x(), float(width));
      Eigen::Vector2f& along = ny == y ? a : b;
      along = along.cwiseMax(step.cwiseAbs());
    }
    return footprint(a + b, at.y(), width);
  }
};

// What a fusion writes besides the panorama, kept from frame to frame: tens of megabytes that
// a fresh allocation would page in again every frame.
struct PanoramaFusion::Scratch {
  std::vector<Placement> placed;          // per camera
  std::vector<std::pair<int, int>> rows;  // (camera, row) over every camera
  PanoramaAccumulator accumulator;
  // The splats that reach each band of panorama rows, listed by each chunk of camera rows:
  // lists[chunk][band], in (camera, row, column) order within a chunk. A band reads its
  // chunks' lists in chunk order, so its pixels receive their samples in that order too.
  std::vector<std::vector<std::vector<SplatRef>>> lists;
};

PanoramaFusion::PanoramaFusion(const CameraRig& rig, const PanoramaFrame& frame, int width)
    : PanoramaFusion(rig, frame, width, {}) {}

PanoramaFusion::PanoramaFusion(const CameraRig& rig, const PanoramaFrame& frame, int width,
                               const std::vector<CameraRays>& given)
    : rig_(rig), width_(width) {
  if (!given.empty()) {
    bool fits = int(given.size()) == rig.size();
    for (int k = 0; fits && k < rig.size(); ++k) fits = sameSize(given[size_t(k)], rig.cameras[size_t(k)]);
    if (!fits) throw Error("PanoramaFusion: the rays given are not one per camera, each its camera's size");
  }
  if (width < 4 || width % 2 || width > 32768)
    throw Error("panorama width must be even and 4 to 32768 px, got " + std::to_string(width));
  scratch_ = std::make_unique<Scratch>(Scratch{{}, {}, PanoramaAccumulator(width), {}});
  for (int k = 0; k < rig.size(); ++k) {
    const BodyPose& pose = rig.poses[size_t(k)];
    const Camera& cam = rig.cameras[size_t(k)];
    // X_pano = Rf^T (R X_cam + p - centre).
    const Eigen::Matrix3d R = frame.R.transpose() * pose.R;
    CameraRays rays = given.empty() ? cameraRays(cam) : given[size_t(k)],
               turned(cam.width, cam.height, Eigen::Vector3f::Constant(kNaNf));
    for (size_t i = 0; i < rays.data.size(); ++i) turned.data[i] = (R * rays.data[i].cast<double>()).cast<float>();
    views_.push_back(
        {std::move(rays), std::move(turned), (frame.R.transpose() * (pose.p - frame.centre)).cast<float>()});
    scratch_->placed.push_back({Image<Eigen::Vector2f>(cam.width, cam.height, Eigen::Vector2f::Constant(kNaNf)),
                                Image<Eigen::Vector2f>(cam.width, cam.height, Eigen::Vector2f::Constant(kNaNf)),
                                ImageF(cam.width, cam.height)});
    for (int y = 0; y < cam.height; ++y) scratch_->rows.emplace_back(k, y);
  }
}

PanoramaFusion::~PanoramaFusion() = default;

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
    checkResult(cameras[size_t(k)], cam, false, "fusePanorama");
    if (!images.empty() && !sameSize(images[size_t(k)], cam))
      throw Error("fusePanorama: image " + std::to_string(k) + " is not its camera's size");
  }
  std::vector<Placement>& placed = scratch_->placed;
  const std::vector<std::pair<int, int>>& rows = scratch_->rows;
  // Rows dealt out in turn (detail::parallelFor), not in contiguous chunks: a fisheye's top
  // and bottom rows hold few pixels of its image circle, its middle rows many.
  detail::parallelFor(int(rows.size()), [&](int i) {
    const auto [k, y] = rows[size_t(i)];
    views_[size_t(k)].placeRow(cameras[size_t(k)], width_, y, placed[size_t(k)]);
  });
  detail::parallelFor(int(rows.size()), [&](int i) {  // the footprints need the neighbours placed
    const auto [k, y] = rows[size_t(i)];
    Placement& place = placed[size_t(k)];
    for (int x = 0; x < place.at.width; ++x)
      if (place.at(x, y).allFinite())
        place.radius(x, y) = views_[size_t(k)].radiusOf(place, cameras[size_t(k)], x, y, width_);
  });
  for (ImageF* image : {&out.range, &out.grey, &out.confidence})
    if (image->width != width_ || image->height != width_ / 2) *image = ImageF(width_, width_ / 2);
  listSplats(cameras, minConfidence);
  PanoramaAccumulator& acc = scratch_->accumulator;
  const int height = width_ / 2, bands = int(scratch_->lists.front().size());
  detail::parallelFor(bands, [&](int band) {
    const int rowBegin = rowOfBand(band, bands, height), rowEnd = rowOfBand(band + 1, bands, height);
    acc.reset(rowBegin, rowEnd);
    auto pass = [&](auto member) {
      for (const std::vector<std::vector<SplatRef>>& chunk : scratch_->lists)
        for (const SplatRef& ref : chunk[size_t(band)]) {
          const Placement& place = placed[size_t(ref.camera)];
          const size_t p = size_t(ref.pixel);
          const float grey =
              images.empty() || images[size_t(ref.camera)].empty() ? kNaNf : images[size_t(ref.camera)].data[p];
          const Splat s{place.at.data[p], place.radius.data[p], place.range.data[p],
                        cameras[size_t(ref.camera)].confidence.data[p], grey};
          (acc.*member)(s, rowBegin, rowEnd);
        }
    };
    pass(&PanoramaAccumulator::bestPass);
    pass(&PanoramaAccumulator::nearestPass);
    pass(&PanoramaAccumulator::meanPass);
    acc.resolve(rowBegin, rowEnd, out);
  });
}

// Each splat listed under every band of panorama rows its footprint reaches (most reach
// one): a band then reads only its own splats. Scanning every camera row that reached a
// band instead read most of the rig's pixels once per band, since a fisheye's row curves
// across much of the sphere's latitude.
void PanoramaFusion::listSplats(const std::vector<DepthResult>& cameras, float minConfidence) {
  const std::vector<std::pair<int, int>>& rows = scratch_->rows;
  // Four bands and four chunks a thread, dealt out in turn: the rig's pixels crowd the
  // panorama's middle rows and the middle rows of its cameras, so equal shares of rows are
  // unequal work.
  const int height = width_ / 2, bands = std::clamp(4 * detail::parallelWorkers(), 1, height);
  const int chunks = std::clamp(4 * detail::parallelWorkers(), 1, int(rows.size()));
  std::vector<std::vector<std::vector<SplatRef>>>& lists = scratch_->lists;
  lists.resize(size_t(chunks));
  detail::parallelFor(chunks, [&](int c) {
    std::vector<std::vector<SplatRef>>& mine = lists[size_t(c)];
    mine.resize(size_t(bands));
    for (std::vector<SplatRef>& list : mine) list.clear();
    const int begin = int(1LL * int(rows.size()) * c / chunks), end = int(1LL * int(rows.size()) * (c + 1) / chunks);
    for (int i = begin; i < end; ++i) {
      const auto [k, y] = rows[size_t(i)];
      const Placement& place = scratch_->placed[size_t(k)];
      const ImageF& confidence = cameras[size_t(k)].confidence;
      for (int x = 0; x < place.at.width; ++x) {
        const size_t p = size_t(y) * size_t(place.at.width) + size_t(x);
        const Eigen::Vector2f at = place.at.data[p], radius = place.radius.data[p];
        if (!at.allFinite() || !(confidence.data[p] >= minConfidence || minConfidence <= 0.f)) continue;
        const int y0 = std::max(0, int(std::ceil(at.y() - radius.y())));
        const int y1 = std::min(height - 1, int(std::floor(at.y() + radius.y())));
        if (y0 > y1) continue;
        for (int b = bandOfRow(y0, bands, height), last = bandOfRow(y1, bands, height); b <= last; ++b)
          mine[size_t(b)].push_back({k, int(p)});
      }
    }
  });
}

Panorama fusePanorama(const CameraRig& rig, const std::vector<DepthResult>& cameras, const std::vector<ImageF>& images,
                      const PanoramaFrame& frame, int width, float minConfidence) {
  return PanoramaFusion(rig, frame, width).fuse(cameras, images, minConfidence);
}

std::vector<RigPoint> mergedPoints(const CameraRig& rig, const std::vector<DepthResult>& cameras,
                                   const std::vector<ImageF>& images, const PanoramaFrame& frame, float minConfidence) {
  if (int(cameras.size()) != rig.size() || (!images.empty() && int(images.size()) != rig.size()))
    throw Error("mergedPoints: " + std::to_string(cameras.size()) + " results and " + std::to_string(images.size()) +
                " images for a rig of " + std::to_string(rig.size()) + " cameras");
  std::vector<RigPoint> points;
  for (int k = 0; k < rig.size(); ++k) {
    const DepthResult& r = cameras[size_t(k)];
    if (!sameSize(r.depth.points, rig.cameras[size_t(k)]) ||
        (!images.empty() && !sameSize(images[size_t(k)], rig.cameras[size_t(k)])))
      throw Error("mergedPoints: the points and image of camera " + std::to_string(k) + " must be its size");
    const Eigen::Matrix3d R = frame.R.transpose() * rig.poses[size_t(k)].R;
    const Eigen::Vector3d p = frame.R.transpose() * (rig.poses[size_t(k)].p - frame.centre);
    for (size_t i = 0; i < r.depth.points.size(); ++i) {
      const Point3f& q = r.depth.points.data[i];
      if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) continue;
      if (!(r.confidence.size() != r.depth.points.size() || r.confidence.data[i] >= minConfidence)) continue;
      const Eigen::Vector3d x = R * Eigen::Vector3d(q.x, q.y, q.z) + p;
      const float grey = images.empty() ? 0.5f : images[size_t(k)].data[i];
      points.push_back({float(x.x()), float(x.y()), float(x.z()), grey});
    }
  }
  return points;
}

}  // namespace cs

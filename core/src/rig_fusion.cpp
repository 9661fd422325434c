// Fusion of a rig's pair results on the host (rig_fusion.hpp): not yet a backend kernel.
#include "curvestereo/rig_fusion.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

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

// The unit rays of a camera's pixels (NaN where it does not unproject).
Image<Eigen::Vector3f> cameraRays(const Camera& cam) {
  const BuiltCamera built(cam);
  Image<Eigen::Vector3f> rays(cam.width, cam.height, Eigen::Vector3f::Constant(kNaNf));
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      Vec3<double> ray;
      if (built.unproject(Vec2<double>(x, y), ray)) rays(x, y) = ray.cast<float>();
    }
  return rays;
}

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
  DepthResult out = *estimates.front();
  const Image<Eigen::Vector3f> rays = cameraRays(cam);
  for (size_t p = 0; p < out.valid.size(); ++p) {
    const DepthResult* best = nullptr;
    for (const DepthResult* e : estimates)
      if (e->valid.data[p] && (!best || weightOf(e->confidence.data[p]) > weightOf(best->confidence.data[p]))) best = e;
    if (!best) continue;  // every output is already NaN there (the first estimate's)
    const double bestDepth = best->depth.radial.data[p];
    double inverseSum = 0, weightSum = 0;
    for (const DepthResult* e : estimates) {
      const double d = e->depth.radial.data[p];
      if (!e->valid.data[p] || !agrees(d, bestDepth)) continue;
      const double w = weightOf(e->confidence.data[p]);
      inverseSum += w / d, weightSum += w;
    }
    const double depth = 1.0 / (inverseSum / weightSum);
    const Eigen::Vector3f ray = rays.data[p];
    out.valid.data[p] = 1;
    out.disparity.data[p] = best->disparity.data[p];
    out.warp.data[p] = best->warp.data[p];
    out.confidence.data[p] = best->confidence.data[p];
    out.depth.radial.data[p] = float(depth);
    out.depth.z.data[p] = std::isfinite(depth) ? float(depth * ray.z()) : INFINITY;
    out.depth.points.data[p] = std::isfinite(depth)
                                   ? Point3f{float(depth * ray.x()), float(depth * ray.y()), float(depth * ray.z())}
                                   : Point3f{kNaNf, kNaNf, kNaNf};
  }
  return out;
}

namespace {

// Every output of pixel p made NaN: DepthResult's contract where valid is 0.
void invalidate(DepthResult& r, size_t p) {
  r.valid.data[p] = 0;
  r.disparity.data[p] = r.depth.radial.data[p] = r.depth.z.data[p] = r.confidence.data[p] = kNaNf;
  r.warp.data[p] = {kNaNf, kNaNf};
  r.depth.points.data[p] = {kNaNf, kNaNf, kNaNf};
}

// Inverse ranges within tolerance of the larger, or within the slack that a fraction of a
// pixel of parallax makes of distant points.
bool consistent(double inverseA, double inverseB, double tolerance) {
  constexpr double kInverseSlack = 0.005;
  return std::abs(inverseA - inverseB) <= tolerance * std::max(inverseA, inverseB) + kInverseSlack;
}

}  // namespace

long long crossCheck(const Rig& pair, DepthResult& forward, const DepthResult& backward, double tolerance) {
  checkResult(forward, pair.cam0, true, "crossCheck");
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
  Eigen::Vector2d at, radius;
  float range, confidence, grey;
};

// The largest half-size of a footprint, in panorama pixels at the equator: larger footprints
// would smear a surface over what lies beside it.
constexpr double kMaxSplatRadius = 3.0;

// The footprint's half-sizes: half the spacing to the neighbours on the same surface, at
// least half a pixel, at most kMaxSplatRadius of the sphere's arc. A column's arc shrinks
// with cos(latitude), so near the poles a camera pixel spans many columns.
Eigen::Vector2d footprint(const Eigen::Vector2d& spacing, double row, int width) {
  const double height = width / 2, latitude = M_PI / 2 - M_PI * (row + 0.5) / height;
  const double columns = kMaxSplatRadius / std::max(std::cos(latitude), 2.0 * kMaxSplatRadius / width);
  return {std::clamp(0.5 * spacing.x(), 0.5, columns), std::clamp(0.5 * spacing.y(), 0.5, kMaxSplatRadius)};
}

// Where camera k's pixels land in the panorama, as forEachSplat's callback receives them.
class SplatSource {
 public:
  SplatSource(const Camera& cam, const BodyPose& pose, const PanoramaFrame& frame, int width)
      : rays_(cameraRays(cam)), width_(width) {
    // X_pano = Rf^T (R X_cam + p - centre).
    R_ = frame.R.transpose() * pose.R;
    p_ = frame.R.transpose() * (pose.p - frame.centre);
  }

  void forEach(const DepthResult& r, const ImageF& image, const std::function<void(const Splat&)>& emit) const {
    const ImageF& radial = r.depth.radial;
    for (int y = 0; y < radial.height; ++y)
      for (int x = 0; x < radial.width; ++x) {
        if (!r.valid(x, y)) continue;
        const Eigen::Vector3d point = pointOf(x, y, radial(x, y));
        if (!point.allFinite()) continue;  // a pixel the camera does not unproject
        const Eigen::Vector2d at = panoramaPixel(point, width_);
        // The steps to the neighbours on the same surface along the camera's rows (a) and
        // columns (b) set the footprint: a box of half-size (|a| + |b|) / 2 per axis covers
        // the cell they span however the camera's grid lies in the panorama, so the panorama
        // has no holes where it samples more finely than the camera.
        Eigen::Vector2d a = Eigen::Vector2d::Zero(), b = Eigen::Vector2d::Zero();
        for (const auto& [nx, ny] :
             {std::pair{x + 1, y}, std::pair{x, y + 1}, std::pair{x - 1, y}, std::pair{x, y - 1}}) {
          if (nx < 0 || ny < 0 || nx >= radial.width || ny >= radial.height || !r.valid(nx, ny)) continue;
          if (!agrees(radial(nx, ny), radial(x, y)) || !rays_(nx, ny).allFinite()) continue;
          Eigen::Vector2d step = panoramaPixel(pointOf(nx, ny, radial(nx, ny)), width_) - at;
          step.x() = std::remainder(step.x(), double(width_));  // across the longitude seam
          Eigen::Vector2d& along = ny == y ? a : b;
          along = along.cwiseMax(step.cwiseAbs());
        }
        const Eigen::Vector2d spacing = a + b;
        const float grey = image.empty() ? kNaNf : image(x, y);
        const float range = std::isfinite(radial(x, y)) ? float(point.norm()) : INFINITY;
        emit({at, footprint(spacing, at.y(), width_), range, r.confidence(x, y), grey});
      }
  }

 private:
  Image<Eigen::Vector3f> rays_;
  int width_;
  Eigen::Matrix3d R_;
  Eigen::Vector3d p_;

  // The point in the panorama frame; a point at infinity is seen along its direction from
  // anywhere, so it is that direction.
  Eigen::Vector3d pointOf(int x, int y, float range) const {
    const Eigen::Vector3d ray = rays_(x, y).cast<double>();
    return std::isfinite(range) ? Eigen::Vector3d(R_ * (double(range) * ray) + p_) : Eigen::Vector3d(R_ * ray);
  }
};

// Three passes over the splats: the best confidence per pixel, the nearest confident range
// (the z-buffer), then the confidence-weighted mean of the samples on that nearest surface.
class PanoramaAccumulator {
 public:
  explicit PanoramaAccumulator(int width)
      : width_(width),
        height_(width / 2),
        bestConfidence_(width, width / 2, -1.f),
        nearest_(width, width / 2, INFINITY),
        rangeSum_(width, width / 2, 0.f),
        greySum_(width, width / 2, 0.f),
        weightSum_(width, width / 2, 0.f),
        greyWeight_(width, width / 2, 0.f) {}

  template <class F>
  void cover(const Splat& s, F&& f) {
    const int x0 = int(std::ceil(s.at.x() - s.radius.x())), x1 = int(std::floor(s.at.x() + s.radius.x()));
    const int y0 = std::max(0, int(std::ceil(s.at.y() - s.radius.y()))),
              y1 = std::min(height_ - 1, int(std::floor(s.at.y() + s.radius.y())));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) f(((x % width_) + width_) % width_, y);
  }

  void bestPass(const Splat& s) {
    cover(s, [&](int x, int y) { bestConfidence_(x, y) = std::max(bestConfidence_(x, y), confidenceOf(s)); });
  }
  void nearestPass(const Splat& s) {
    cover(s, [&](int x, int y) {
      if (confident(s, x, y)) nearest_(x, y) = std::min(nearest_(x, y), s.range);
    });
  }
  void meanPass(const Splat& s) {
    cover(s, [&](int x, int y) {
      if (!confident(s, x, y) || !agrees(s.range, nearest_(x, y))) return;
      const float w = float(weightOf(s.confidence));
      // Inverse range, so that +inf samples average to +inf without NaN.
      rangeSum_(x, y) += w / s.range;
      weightSum_(x, y) += w;
      if (std::isfinite(s.grey)) greySum_(x, y) += w * s.grey, greyWeight_(x, y) += w;
    });
  }

  Panorama result() const {
    Panorama p{ImageF(width_, height_, kNaNf), ImageF(width_, height_, kNaNf), ImageF(width_, height_, kNaNf)};
    for (size_t k = 0; k < p.range.size(); ++k) {
      if (!(weightSum_.data[k] > 0)) continue;
      p.range.data[k] = weightSum_.data[k] / rangeSum_.data[k];
      p.confidence.data[k] = bestConfidence_.data[k];
      if (greyWeight_.data[k] > 0) p.grey.data[k] = greySum_.data[k] / greyWeight_.data[k];
    }
    return p;
  }

 private:
  int width_, height_;
  ImageF bestConfidence_, nearest_, rangeSum_, greySum_, weightSum_, greyWeight_;

  static float confidenceOf(const Splat& s) { return std::isfinite(s.confidence) ? s.confidence : 0.f; }
  // A sample well below the best one there is a likely mismatch: it must not hide the surface.
  bool confident(const Splat& s, int x, int y) const { return confidenceOf(s) >= 0.5f * bestConfidence_(x, y); }
};

}  // namespace

Panorama fusePanorama(const CameraRig& rig, const std::vector<DepthResult>& cameras, const std::vector<ImageF>& images,
                      const PanoramaFrame& frame, int width, float minConfidence) {
  if (width < 4 || width % 2 || width > 32768)
    throw Error("panorama width must be even and 4 to 32768 px, got " + std::to_string(width));
  if (int(cameras.size()) != rig.size() || (!images.empty() && int(images.size()) != rig.size()))
    throw Error("fusePanorama: " + std::to_string(cameras.size()) + " results and " + std::to_string(images.size()) +
                " images for a rig of " + std::to_string(rig.size()) + " cameras");
  std::vector<SplatSource> sources;
  for (int k = 0; k < rig.size(); ++k) {
    checkResult(cameras[size_t(k)], rig.cameras[size_t(k)], false, "fusePanorama");
    if (!images.empty() && !sameSize(images[size_t(k)], rig.cameras[size_t(k)]))
      throw Error("fusePanorama: image " + std::to_string(k) + " is not its camera's size");
    sources.emplace_back(rig.cameras[size_t(k)], rig.poses[size_t(k)], frame, width);
  }
  PanoramaAccumulator acc(width);
  auto pass = [&](auto member) {
    for (int k = 0; k < rig.size(); ++k)
      sources[size_t(k)].forEach(cameras[size_t(k)], images.empty() ? ImageF() : images[size_t(k)],
                                 [&](const Splat& s) {
                                   if (s.confidence >= minConfidence || minConfidence <= 0.f) (acc.*member)(s);
                                 });
  };
  pass(&PanoramaAccumulator::bestPass);
  pass(&PanoramaAccumulator::nearestPass);
  pass(&PanoramaAccumulator::meanPass);
  return acc.result();
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

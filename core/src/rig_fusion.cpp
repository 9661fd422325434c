// Fusion of a rig's pair results on the host (rig_fusion.hpp): each camera's estimates, the
// pairs' cross-check, the panorama's frame and pixels, the merged points. The panorama itself
// runs on a backend (stereo/panorama_fusion.cpp).
#include "curvestereo/rig_fusion.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "curvestereo/fusion_checks.hpp"
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

void checkFusionInput(const DepthResult& r, const Camera& cam, bool allOutputs, const char* what) {
  const bool sizes = sameSize(r.valid, cam) && sameSize(r.depth.radial, cam) && sameSize(r.confidence, cam);
  const bool others = !allOutputs || (sameSize(r.disparity, cam) && sameSize(r.warp, cam) && sameSize(r.depth.z, cam) &&
                                      sameSize(r.depth.points, cam));
  if (!sizes || !others)
    throw Error(std::string(what) + ": a result for a camera of " + std::to_string(cam.width) + "x" +
                std::to_string(cam.height) + " px needs " +
                (allOutputs ? "every output" : "valid, depth and confidence") + " at that size (Stereo::setOutputs)");
}

DepthResult fuseCameraEstimates(const Camera& cam, const std::vector<const DepthResult*>& estimates) {
  if (estimates.empty()) throw Error("fuseCameraEstimates: no estimates");
  for (const DepthResult* e : estimates) checkFusionInput(*e, cam, true, "fuseCameraEstimates");
  DepthResult out;
  fuseCameraEstimates(cam, estimates, cameraRays(cam), out);
  return out;
}

namespace {

// The point a pixel of the pair's camera 0 sees (its unit ray at `depth`) in camera 1's
// frame; a point at infinity is its direction, and stays at infinity there.
Eigen::Vector3d carriedInto(const Rig& pair, double depth, const Eigen::Vector3d& ray) {
  return std::isfinite(depth) ? Eigen::Vector3d(pair.R * (depth * ray) + pair.t) : Eigen::Vector3d(pair.R * ray);
}

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

// Where camera pixel (x, y) lies in an estimate of a window, if it has a depth there.
bool covers(const PlacedEstimate& e, int x, int y, size_t& at) {
  const int u = x - e.window.x0, v = y - e.window.y0;
  if (u < 0 || v < 0 || u >= e.window.width || v >= e.window.height) return false;
  at = size_t(v) * size_t(e.window.width) + size_t(u);
  return e.result->valid.data[at] != 0;
}

// Pixel (x, y), index p, of `out` from the estimates: the most confident one, averaged with
// those that agree.
void fusePixel(const std::vector<PlacedEstimate>& estimates, const Eigen::Vector3f& ray, bool withFlow, bool withPoints,
               int x, int y, size_t p, DepthResult& out) {
  const DepthResult* best = nullptr;
  size_t bestAt = 0, at = 0;
  double bestWeight = 0;
  int covering = 0;
  for (const PlacedEstimate& e : estimates) {
    if (!covers(e, x, y, at)) continue;
    ++covering;
    const double w = weightOf(e.result->confidence.data[at]);
    if (!best || w > bestWeight) best = e.result, bestAt = at, bestWeight = w;
  }
  if (!best) return invalidate(out, p);
  const double bestDepth = best->depth.radial.data[bestAt];
  double depth = bestDepth;  // alone: as it is (most pixels, and no division)
  if (covering > 1) {
    double inverseSum = 0, weightSum = 0;
    for (const PlacedEstimate& e : estimates) {
      if (!covers(e, x, y, at)) continue;
      const double d = e.result->depth.radial.data[at];
      if (!agrees(d, bestDepth)) continue;
      const double w = weightOf(e.result->confidence.data[at]);
      inverseSum += w / d, weightSum += w;
    }
    depth = 1.0 / (inverseSum / weightSum);
  }
  out.valid.data[p] = 1;
  if (withFlow) out.disparity.data[p] = best->disparity.data[bestAt], out.warp.data[p] = best->warp.data[bestAt];
  out.confidence.data[p] = best->confidence.data[bestAt];
  out.depth.radial.data[p] = float(depth);
  if (!withPoints) return;
  out.depth.z.data[p] = std::isfinite(depth) ? float(depth * ray.z()) : INFINITY;
  out.depth.points.data[p] = std::isfinite(depth)
                                 ? Point3f{float(depth * ray.x()), float(depth * ray.y()), float(depth * ray.z())}
                                 : Point3f{kNaNf, kNaNf, kNaNf};
}

}  // namespace

void fuseCameraEstimates(const Camera& cam, const std::vector<const DepthResult*>& estimates, const CameraRays& rays,
                         DepthResult& out) {
  std::vector<PlacedEstimate> placed;
  for (const DepthResult* e : estimates) placed.push_back({e, {}});
  fuseCameraEstimates(cam, placed, rays, out);
}

void fuseCameraEstimates(const Camera& cam, const std::vector<PlacedEstimate>& estimates, const CameraRays& rays,
                         DepthResult& out, bool withPoints) {
  if (estimates.empty()) throw Error("fuseCameraEstimates: no estimates");
  std::vector<PlacedEstimate> placed = estimates;
  bool withFlow = true;
  for (PlacedEstimate& e : placed) {
    e.window = e.window.orWhole(cam);
    const Camera part = cam.cropped(e.window.x0, e.window.y0, e.window.width, e.window.height);
    checkFusionInput(*e.result, part, false, "fuseCameraEstimates");
    withFlow = withFlow && sameSize(e.result->disparity, part) && sameSize(e.result->warp, part);
  }
  if (!sameSize(rays, cam)) throw Error("fuseCameraEstimates: the rays are not the camera's size");
  const DepthResult& first = *placed.front().result;
  out.stages = first.stages;
  out.totalMs = first.totalMs;
  out.warm = first.warm, out.redone = first.redone;
  out.consistentShare = first.consistentShare, out.meanConfidence = first.meanConfidence;
  out.lrPassShare = first.lrPassShare;
  sizeFor(out.valid, cam), sizeFor(out.confidence, cam), sizeFor(out.depth.radial, cam);
  if (withPoints) {
    sizeFor(out.depth.z, cam), sizeFor(out.depth.points, cam);
  } else {
    out.depth.z = ImageF(), out.depth.points = Image<Point3f>();
  }
  if (withFlow) {
    sizeFor(out.disparity, cam), sizeFor(out.warp, cam);
  } else {
    out.disparity = ImageF(), out.warp = FlowImage();
  }
  inChunks(cam.height, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < cam.width; ++x) {
        const size_t p = size_t(y) * size_t(cam.width) + size_t(x);
        fusePixel(placed, rays.data[p], withFlow, withPoints, x, y, p, out);
      }
  });
}

long long completeFromPartner(const Rig& pair, const PlacedEstimate& from, const CameraRays& raysI,
                              const CameraRays& raysJ, const std::vector<uint8_t>& open, DepthResult& out) {
  const Camera& j = pair.cam1;
  const ImageWindow w = from.window.orWhole(pair.cam0);
  checkFusionInput(out, j, false, "completeFromPartner");
  checkFusionInput(*from.result, pair.cam0.cropped(w.x0, w.y0, w.width, w.height), false, "completeFromPartner");
  if (!sameSize(raysI, pair.cam0) || !sameSize(raysJ, j) || open.size() != size_t(j.width) * size_t(j.height))
    throw Error("completeFromPartner: the rays or the open pixels are not their camera's size");
  const BuiltCamera built(j);
  const bool withPoints = sameSize(out.depth.z, j) && sameSize(out.depth.points, j);
  const bool withFlow = sameSize(out.disparity, j) && sameSize(out.warp, j);
  long long count = 0;
  for (int v = 0; v < w.height; ++v)
    for (int u = 0; u < w.width; ++u) {
      const size_t at = size_t(v) * size_t(w.width) + size_t(u);
      const float depth = from.result->depth.radial.data[at];
      const Eigen::Vector3d ray = raysI(w.x0 + u, w.y0 + v).cast<double>();
      if (!from.result->valid.data[at] || std::isnan(depth) || !ray.allFinite()) continue;
      const bool finite = std::isfinite(depth);
      const Eigen::Vector3d X = carriedInto(pair, depth, ray);
      Vec2<double> px;
      if (!built.project(X, px) || !built.inImage(px)) continue;
      const float range = finite ? float(X.norm()) : INFINITY;
      const int x0 = int(std::floor(px.x())), y0 = int(std::floor(px.y()));
      for (int y = y0; y <= y0 + 1; ++y)
        for (int x = x0; x <= x0 + 1; ++x) {
          if (x < 0 || y < 0 || x >= j.width || y >= j.height) continue;
          const size_t p = size_t(y) * size_t(j.width) + size_t(x);
          // out itself is the z-buffer: what an earlier point, or an earlier partner, left there.
          if (!open[p] || (out.valid.data[p] && !(range < out.depth.radial.data[p]))) continue;
          count += !out.valid.data[p];
          out.valid.data[p] = 1;
          out.depth.radial.data[p] = range;
          out.confidence.data[p] = from.result->confidence.data[at];
          if (withFlow) out.disparity.data[p] = kNaNf, out.warp.data[p] = {kNaNf, kNaNf};
          if (!withPoints) continue;
          const Eigen::Vector3f& r = raysJ.data[p];
          out.depth.z.data[p] = finite ? range * r.z() : INFINITY;
          out.depth.points.data[p] =
              finite ? Point3f{range * r.x(), range * r.y(), range * r.z()} : Point3f{kNaNf, kNaNf, kNaNf};
        }
    }
  return count;
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
  checkFusionInput(forward, pair.cam0, false, "crossCheck");
  checkFusionInput(backward, pair.cam1, false, "crossCheck");
  const Image<Eigen::Vector3f> rays = cameraRays(pair.cam0);
  const BuiltCamera other(pair.cam1);
  long long invalidated = 0;
  for (int y = 0; y < forward.valid.height; ++y)
    for (int x = 0; x < forward.valid.width; ++x) {
      const double depth = forward.depth.radial(x, y);
      const Eigen::Vector3d ray = rays(x, y).cast<double>();
      if (!forward.valid(x, y) || !ray.allFinite()) continue;
      const Eigen::Vector3d inOther = carriedInto(pair, depth, ray);
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

double panoramaParallaxSlack(const CameraRig& rig) {
  if (rig.size() < 2 || rig.poses.size() != rig.cameras.size()) return 0.0;
  double baselines = 0, pxPerRadian = INFINITY;
  for (int k = 0; k < rig.size(); ++k) {
    double nearest = INFINITY;
    for (int j = 0; j < rig.size(); ++j)
      if (j != k) nearest = std::min(nearest, (rig.poses[size_t(j)].p - rig.poses[size_t(k)].p).norm());
    baselines += nearest;
    const Camera& cam = rig.cameras[size_t(k)];
    const BuiltCamera built(cam);
    Vec3<double> a, b;
    const double cx = 0.5 * (cam.width - 1), cy = 0.5 * (cam.height - 1);
    if (!built.unproject(Vec2<double>(cx, cy), a) || !built.unproject(Vec2<double>(cx + 1, cy), b)) continue;
    const double angle = std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
    if (angle > 0) pxPerRadian = std::min(pxPerRadian, 1.0 / angle);
  }
  if (!std::isfinite(pxPerRadian)) return 0.0;  // no camera unprojects its centre: no slack
  return kPanoramaParallaxPx / (baselines / double(rig.size()) * pxPerRadian);
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

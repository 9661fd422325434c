#include "curvestereo/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "curvestereo/triangulate.hpp"

namespace cs {

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();

bool hasGroundTruth(float depth) { return std::isfinite(depth) && depth > 0; }

// Camera 1 sees the point when one of the depth pixels around its projection holds the
// same surface (2 % relative): robust to the interpolation at depth edges.
bool agreesWithSecondView(const ImageF& depthRight, const Vec2<double>& px1, double range) {
  int x0 = int(std::floor(px1.x())), y0 = int(std::floor(px1.y()));
  for (int dy = 0; dy <= 1; ++dy)
    for (int dx = 0; dx <= 1; ++dx) {
      int x = x0 + dx, y = y0 + dy;
      if (!depthRight.inside(x, y)) continue;
      float d = depthRight(x, y);
      if (hasGroundTruth(d) && std::abs(d - range) <= 0.02 * range) return true;
    }
  return false;
}

}  // namespace

FlowImage groundTruthWarp(const Rig& rig, const ImageF& depthLeft) {
  const Eigen::Vector3d tPrime = rig.tPrime();
  const BuiltCamera cam0(rig.cam0);
  FlowImage w(depthLeft.width, depthLeft.height, Vec2f{kNaN, kNaN});
  for (int y = 0; y < depthLeft.height; ++y)
    for (int x = 0; x < depthLeft.width; ++x) {
      float d = depthLeft(x, y);
      Vec2<double> wx;
      if (hasGroundTruth(d) && warpFromDepth(cam0, tPrime, Vec2<double>(x, y), d, wx))
        w(x, y) = {float(wx.x()), float(wx.y())};
    }
  return w;
}

ImageU8 nonOccludedMask(const Rig& rig, const ImageF& depthLeft, const ImageF* depthRight) {
  ImageU8 noc(depthLeft.width, depthLeft.height, 0);
  const BuiltCamera cam0(rig.cam0), cam1(rig.cam1);
  for (int y = 0; y < depthLeft.height; ++y)
    for (int x = 0; x < depthLeft.width; ++x) {
      float d = depthLeft(x, y);
      Vec3<double> ray;
      if (!hasGroundTruth(d) || !cam0.unproject(Vec2<double>(x, y), ray)) continue;
      Vec3<double> X1 = rig.R * (double(d) * ray) + rig.t;
      Vec2<double> px1;
      if (!cam1.project(X1, px1) || !cam1.inImage(px1)) continue;
      if (depthRight && !agreesWithSecondView(*depthRight, px1, X1.norm())) continue;
      noc(x, y) = 1;
    }
  return noc;
}

Metrics evaluate(const Rig& rig, const FlowImage& est, const ImageF& estDepth, const ImageF& depthLeft,
                 const ImageF* depthRight, ImageF* errorMap) {
  if (est.width != depthLeft.width || est.height != depthLeft.height)
    throw Error("evaluation: estimate and ground truth differ in size");
  const FlowImage gt = groundTruthWarp(rig, depthLeft);
  const ImageU8 noc = nonOccludedMask(rig, depthLeft, depthRight);
  if (errorMap) *errorMap = ImageF(est.width, est.height, kNaN);

  struct Acc {
    long long n = 0, over1 = 0, over3 = 0;
    double sum = 0;
    void add(double e) {
      ++n;
      over1 += e > 1.0;
      over3 += e > 3.0;
      sum += std::isfinite(e) ? e : 0.0;
    }
  } all, nonOcc;
  long long estimated = 0, depthCount = 0, skyPixels = 0, skyFar = 0;
  double absRelSum = 0;

  for (int y = 0; y < est.height; ++y)
    for (int x = 0; x < est.width; ++x) {
      Vec2f g = gt(x, y), e = est(x, y);
      if (std::isinf(depthLeft(x, y)) && depthLeft(x, y) > 0) {
        ++skyPixels;
        skyFar += !(std::fabs(estDepth(x, y)) < INFINITY);  // NaN or +inf
      }
      if (std::isnan(g.x)) continue;
      bool has = std::isfinite(e.x) && std::isfinite(e.y);
      // A missing estimate is an error of infinite size: it counts in tau, not in the mean.
      double err = has ? std::hypot(double(e.x) - g.x, double(e.y) - g.y) : INFINITY;
      all.add(err);
      if (noc(x, y)) nonOcc.add(err);
      if (errorMap) (*errorMap)(x, y) = float(err);
      if (!has) continue;
      ++estimated;
      float de = estDepth(x, y), dg = depthLeft(x, y);
      if (!std::isnan(de)) {
        ++depthCount;
        absRelSum += std::isfinite(de) ? std::min(1.0, std::abs(double(de) - dg) / dg) : 1.0;
      }
    }

  Metrics m;
  auto pct = [](long long k, long long n) { return n ? 100.0 * double(k) / double(n) : 0.0; };
  m.evaluated = all.n;
  m.nonOccluded = nonOcc.n;
  m.tau1 = pct(all.over1, all.n);
  m.tau3 = pct(all.over3, all.n);
  m.epe = estimated ? all.sum / double(estimated) : 0.0;
  m.tau1Noc = pct(nonOcc.over1, nonOcc.n);
  m.tau3Noc = pct(nonOcc.over3, nonOcc.n);
  long long nocEstimated = 0;
  for (int y = 0; y < est.height; ++y)
    for (int x = 0; x < est.width; ++x)
      if (noc(x, y) && !std::isnan(gt(x, y).x) && std::isfinite(est(x, y).x)) ++nocEstimated;
  m.epeNoc = nocEstimated ? nonOcc.sum / double(nocEstimated) : 0.0;
  m.absRel = depthCount ? absRelSum / double(depthCount) : 0.0;
  m.density = pct(estimated, all.n);
  m.skyPixels = skyPixels;
  m.sky = skyPixels ? pct(skyFar, skyPixels) : kNaN;
  return m;
}

namespace {

// tau>k (percent) of the first share of `errors`, already in rank order.
std::vector<double> tauOfRanked(const std::vector<float>& errors, const std::vector<double>& keptPercent, double k) {
  std::vector<double> tau;
  for (double kept : keptPercent) {
    const size_t n = size_t(std::ceil(double(errors.size()) * kept / 100.0 - 1e-9));
    long long bad = 0;
    for (size_t i = 0; i < n; ++i) bad += !(errors[i] <= k);
    tau.push_back(n ? 100.0 * double(bad) / double(n) : std::numeric_limits<double>::quiet_NaN());
  }
  return tau;
}

double meanOfCurve(const std::vector<double>& x, const std::vector<double>& y) {
  double area = 0;
  for (size_t i = 1; i < x.size(); ++i) area += 0.5 * (y[i] + y[i - 1]) * std::fabs(x[i] - x[i - 1]);
  return area / std::fabs(x.back() - x.front());
}

}  // namespace

Sparsification sparsification(const ImageF& errorMap, const ImageF& confidence, double k) {
  if (errorMap.width != confidence.width || errorMap.height != confidence.height)
    throw Error("sparsification: the error map and the confidence differ in size");
  struct Ranked {
    float confidence, error;
  };
  std::vector<Ranked> pixels;
  for (size_t i = 0; i < errorMap.data.size(); ++i) {
    const float e = errorMap.data[i];
    if (std::isnan(e)) continue;
    const float c = confidence.data[i];
    const bool estimated = std::isfinite(e) && !std::isnan(c);
    pixels.push_back({estimated ? c : -std::numeric_limits<float>::infinity(), e});
  }
  Sparsification s;
  for (int kept = 100; kept >= 50; kept -= 5) s.keptPercent.push_back(kept);
  s.evaluated = (long long)pixels.size();
  std::stable_sort(pixels.begin(), pixels.end(),
                   [](const Ranked& a, const Ranked& b) { return a.confidence > b.confidence; });
  std::vector<float> errors;
  for (const Ranked& p : pixels) errors.push_back(p.error);
  s.tau = tauOfRanked(errors, s.keptPercent, k);
  std::sort(errors.begin(), errors.end());
  s.oracleTau = tauOfRanked(errors, s.keptPercent, k);
  s.area = meanOfCurve(s.keptPercent, s.tau);
  s.oracleArea = meanOfCurve(s.keptPercent, s.oracleTau);
  return s;
}

double maskedTau(const ImageF& errorMap, const ImageU8& mask, double k, long long* pixels) {
  if (mask.width != errorMap.width || mask.height != errorMap.height)
    throw Error("evaluation: mask and error map differ in size");
  long long n = 0, bad = 0;
  for (size_t i = 0; i < errorMap.size(); ++i) {
    const float e = errorMap.data[i];
    if (!mask.data[i] || std::isnan(e)) continue;
    ++n;
    bad += e > k;  // +inf (no estimate) included
  }
  if (pixels) *pixels = n;
  return n ? 100.0 * double(bad) / double(n) : std::numeric_limits<double>::quiet_NaN();
}

namespace {

// An estimate of radial depth: finite and positive, or +inf (a point at infinity).
bool isEstimate(float depth) { return depth > 0 && !std::isnan(depth); }

// The signed relative error of an estimate, capped at 1 (as absRel is).
double relativeError(float est, float gt) { return std::isfinite(est) ? std::min(1.0, (double(est) - gt) / gt) : 1.0; }

}  // namespace

double flicker(const Camera& cam0, const ImageF& estPrev, const ImageF& gtPrev, const ImageF& est, const ImageF& gt,
               const ImageU8* moverPrev, const ImageU8* mover, const Motion& prevToCurrent, long long* points) {
  const int w = cam0.width, h = cam0.height;
  auto check = [&](int iw, int ih, const char* what) {
    if (iw != w || ih != h)
      throw Error(std::string("flicker: ") + what + " is " + std::to_string(iw) + "x" + std::to_string(ih) +
                  ", camera 0 " + std::to_string(w) + "x" + std::to_string(h));
  };
  check(estPrev.width, estPrev.height, "the previous estimate");
  check(gtPrev.width, gtPrev.height, "the previous ground truth");
  check(est.width, est.height, "the estimate");
  check(gt.width, gt.height, "the ground truth");
  if (moverPrev) check(moverPrev->width, moverPrev->height, "the previous mover mask");
  if (mover) check(mover->width, mover->height, "the mover mask");

  const BuiltCamera cam(cam0);
  // Frame k's camera coordinates into frame k-1's: the inverse of prevToCurrent.
  const Eigen::Matrix3d Rback = prevToCurrent.R.transpose();
  const Eigen::Vector3d tback = -(Rback * prevToCurrent.t);
  long long n = 0;
  double sum = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float g = gt(x, y), e = est(x, y);
      if (!hasGroundTruth(g) || !isEstimate(e) || (mover && (*mover)(x, y))) continue;
      Vec3<double> ray;
      if (!cam.unproject(Vec2<double>(x, y), ray)) continue;
      const Eigen::Vector3d Xprev = Rback * (double(g) * ray) + tback;
      Vec2<double> px;
      if (!cam.project(Xprev, px) || !cam.inImage(px)) continue;
      const int xp = int(std::lround(px.x())), yp = int(std::lround(px.y()));
      if (!gtPrev.inside(xp, yp)) continue;
      const float gp = gtPrev(xp, yp), ep = estPrev(xp, yp);
      if (!hasGroundTruth(gp) || !isEstimate(ep) || (moverPrev && (*moverPrev)(xp, yp))) continue;
      const double range = Xprev.norm();
      if (std::abs(double(gp) - range) > 0.02 * range) continue;  // occluded in frame k-1
      sum += std::abs(relativeError(e, g) - relativeError(ep, gp));
      ++n;
    }
  if (points) *points = n;
  return n ? sum / double(n) : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace cs

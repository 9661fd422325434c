#include "plain_fill.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "curvestereo/parallel.hpp"

#include "curvestereo/triangulate.hpp"

namespace cs {

namespace {

constexpr int kRansacTrials = 512;

enum Texture : uint8_t { kUnknown, kPlain, kTextured };

// Plain: the grey levels of the window around (Backend::plainSupport's variance) vary no
// more than twice the noise would make them (a noise-only window's spread is the noise
// itself). Textured: more than four times. Unknown: outside the mask, at its rim and in
// between.
std::vector<uint8_t> texturePixels(const std::vector<float>& support, float noise) {
  const float limit = 4.f * noise * noise;
  std::vector<uint8_t> texture(support.size() / kPlainSupportChannels, kUnknown);
  for (size_t i = 0; i < texture.size(); ++i) {
    const float variance = support[kPlainSupportChannels * i + 5];
    if (variance >= 0.f) texture[i] = variance < limit ? kPlain : variance > 4.f * limit ? kTextured : kUnknown;
  }
  return texture;
}

// 4-connected regions of plain pixels: each pixel's region index (-1: none), regions listed.
std::vector<std::vector<int>> plainRegions(int width, int height, const std::vector<uint8_t>& plain,
                                           std::vector<int>& label) {
  label.assign(plain.size(), -1);
  std::vector<std::vector<int>> regions;
  std::vector<int> stack;
  for (int start = 0; start < int(plain.size()); ++start) {
    if (plain[size_t(start)] != kPlain || label[size_t(start)] >= 0) continue;
    const int id = int(regions.size());
    regions.emplace_back();
    std::vector<int>& region = regions.back();
    label[size_t(start)] = id;
    stack.push_back(start);
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      region.push_back(i);
      const int x = i % width, y = i / width;
      const int next[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
      for (const auto& p : next) {
        if (p[0] < 0 || p[1] < 0 || p[0] >= width || p[1] >= height) continue;
        const int j = p[1] * width + p[0];
        if (plain[size_t(j)] != kPlain || label[size_t(j)] >= 0) continue;
        label[size_t(j)] = id;
        stack.push_back(j);
      }
    }
  }
  return regions;
}

// A pixel's ray, inverse depth and how far (level px) its image moves per unit of inverse
// depth there: the scale that turns an inverse-depth residual into pixels.
struct Sample {
  Eigen::Vector3d ray;
  double q = 0, pxPerQ = 0;
};

bool pxPerInverseDepth(const BuiltCamera& cam, const Eigen::Vector3d& tPrime, const Eigen::Vector3d& ray, double q,
                       double& pxPerQ) {
  Vec2<double> px;
  Mat23<double> J;
  if (!cam.project(Vec3<double>(ray + q * tPrime), px, &J)) return false;
  pxPerQ = (J * tPrime).norm();
  return pxPerQ > 0;
}

// The non-plain masked pixels within `radius` of the region: its border, where the images
// had texture to match.
std::vector<int> borderOf(int width, int height, const std::vector<int>& region, int id, const std::vector<int>& label,
                          const std::vector<uint8_t>& plain, int radius, std::vector<int>& stamp) {
  std::vector<int> border;
  for (int i : region) {
    const int x = i % width, y = i / width;
    const bool inner = x > 0 && y > 0 && x + 1 < width && y + 1 < height && label[size_t(i - 1)] == id &&
                       label[size_t(i + 1)] == id && label[size_t(i - width)] == id && label[size_t(i + width)] == id;
    if (inner) continue;
    for (int dy = -radius; dy <= radius; ++dy)
      for (int dx = -radius; dx <= radius; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
        const int j = ny * width + nx;
        if (plain[size_t(j)] != kTextured || stamp[size_t(j)] == id) continue;
        stamp[size_t(j)] = id;
        border.push_back(j);
      }
  }
  return border;
}

struct PlaneFit {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();  // q = a . ray
  std::vector<int> inliers;
};

double residualPx(const Sample& s, const Eigen::Vector3d& a) { return std::abs(a.dot(s.ray) - s.q) * s.pxPerQ; }

// Least squares in pixels over the given samples: min sum (pxPerQ (a . ray - q))^2.
bool fitPlane(const std::vector<Sample>& samples, const std::vector<int>& which, Eigen::Vector3d& a,
              Eigen::Matrix3d* normal = nullptr) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (int k : which) {
    const Sample& s = samples[size_t(k)];
    const double w2 = s.pxPerQ * s.pxPerQ;
    A += w2 * s.ray * s.ray.transpose();
    b += w2 * s.q * s.ray;
  }
  Eigen::LDLT<Eigen::Matrix3d> ldlt(A);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-12)) return false;
  a = ldlt.solve(b);
  if (normal) *normal = A;
  return a.allFinite();
}

// The plane most of the border agrees with: RANSAC over triples (a fixed sequence of
// draws, scored on the pool, the first best kept: every run fills alike), refined on its
// inliers. MSAC scoring: each sample costs its squared residual, capped at the inlier bound,
// so among planes with as many inliers the one they fit closer wins.
PlaneFit ransacPlane(const std::vector<Sample>& samples, double inlierPx, uint32_t seed) {
  PlaneFit best;
  const int n = int(samples.size());
  if (n < 3) return best;
  uint32_t state = seed * 2654435761u + 1u;
  auto draw = [&] {
    state = state * 1664525u + 1013904223u;
    return int((uint64_t(state >> 8) * uint64_t(n)) >> 24);
  };
  std::vector<std::array<int, 3>> triples(kRansacTrials);
  for (auto& t : triples) t = {draw(), draw(), draw()};
  std::vector<double> costs(kRansacTrials, INFINITY);
  std::vector<Eigen::Vector3d> planes(kRansacTrials);
  detail::parallelFor(
      kRansacTrials,
      [&](int trial) {
        const auto [i, j, k] = triples[size_t(trial)];
        if (i == j || j == k || i == k) return;
        Eigen::Matrix3d M;
        M.row(0) = samples[size_t(i)].ray.transpose();
        M.row(1) = samples[size_t(j)].ray.transpose();
        M.row(2) = samples[size_t(k)].ray.transpose();
        Eigen::FullPivLU<Eigen::Matrix3d> lu(M);
        if (!lu.isInvertible()) return;
        const Eigen::Vector3d a =
            lu.solve(Eigen::Vector3d(samples[size_t(i)].q, samples[size_t(j)].q, samples[size_t(k)].q));
        double cost = 0;
        for (const Sample& s : samples) cost += std::min(std::pow(residualPx(s, a), 2), inlierPx * inlierPx);
        costs[size_t(trial)] = cost;
        planes[size_t(trial)] = a;
      },
      8);
  const size_t winner = size_t(std::min_element(costs.begin(), costs.end()) - costs.begin());
  if (!std::isfinite(costs[winner])) return best;
  best.a = planes[winner];
  for (int m = 0; m < n; ++m)
    if (residualPx(samples[size_t(m)], best.a) < inlierPx) best.inliers.push_back(m);
  if (best.inliers.size() < 3 || !fitPlane(samples, best.inliers, best.a)) return PlaneFit{};
  best.inliers.clear();
  for (int m = 0; m < n; ++m)
    if (residualPx(samples[size_t(m)], best.a) < inlierPx) best.inliers.push_back(m);
  return best;
}

// The region's border samples: each support pixel's full-resolution ray, the inverse depth
// its warp triangulates to, and its pixels per unit of inverse depth.
std::vector<Sample> borderSamples(const BuiltCamera& cam, const Eigen::Vector3d& tPrime, const std::vector<int>& border,
                                  const std::vector<float>& support, double minConfidence) {
  std::vector<Sample> samples;
  for (int i : border) {
    const float* b = &support[kPlainSupportChannels * size_t(i)];
    if (!(b[4] >= minConfidence)) continue;
    const Vec2<double> x(b[0], b[1]), w(b[2], b[3]);
    const double radial = triangulateRadial(cam, tPrime, x, w);
    Sample s;
    Vec3<double> ray;
    if (std::isnan(radial) || !cam.unproject(x, ray)) continue;
    s.ray = ray;
    s.q = std::isinf(radial) ? 0.0 : 1.0 / radial;
    if (pxPerInverseDepth(cam, tPrime, s.ray, s.q, s.pxPerQ)) samples.push_back(s);
  }
  return samples;
}

// The pixels of the region the plane fills: none when it lies behind a ray of the region or
// nearer than the nearest sphere (it is not the region's surface); else those where the
// border fixes it to maxDeviationPx (the rest, far from any border that voted, keep the
// solver's estimate). In fixed pieces on the pool, joined in order.
std::vector<int> filledPixels(const BuiltCamera& cam, const Eigen::Vector3d& tPrime, const std::vector<int>& region,
                              const PlainRays& rays, const Eigen::Vector3d& a, const Eigen::Matrix3d& covariance,
                              const PlainFillParams& p) {
  constexpr size_t kPiece = 1024;
  const size_t pieces = (region.size() + kPiece - 1) / kPiece;
  std::vector<std::vector<int>> known(pieces);
  std::vector<uint8_t> behind(pieces, 0);
  detail::parallelPieces(region.size(), kPiece, [&](size_t begin, size_t end) {
    const size_t piece = begin / kPiece;
    for (size_t k = begin; k < end && !behind[piece]; ++k) {
      const int i = region[k];
      if (!rays.valid[size_t(i)]) continue;
      const Eigen::Vector3d ray = rays.ray[size_t(i)].cast<double>();
      const double q = a.dot(ray);
      double pxPerQ;
      if (!(q >= 0.0) || q > p.qMax || !pxPerInverseDepth(cam, tPrime, ray, q, pxPerQ)) {
        behind[piece] = 1;
        break;
      }
      if (pxPerQ * std::sqrt(ray.dot(covariance * ray)) <= p.maxDeviationPx) known[piece].push_back(i);
    }
  });
  std::vector<int> all;
  for (size_t k = 0; k < pieces; ++k) {
    if (behind[k]) return {};
    all.insert(all.end(), known[k].begin(), known[k].end());
  }
  return all;
}

}  // namespace

PlainRays plainRays(const Camera& camera0, int width, int height) {
  PlainRays rays;
  rays.ray.resize(size_t(width) * height);
  rays.valid.assign(rays.ray.size(), 0);
  const BuiltCamera cam(camera0);
  const double sx = double(camera0.width) / width, sy = double(camera0.height) / height;
  detail::parallelFor(
      height,
      [&](int y) {
        for (int x = 0; x < width; ++x) {
          Vec3<double> ray;
          const size_t i = size_t(y) * width + x;
          if (!cam.unproject(Vec2<double>((x + 0.5) * sx - 0.5, (y + 0.5) * sy - 0.5), ray)) continue;
          rays.ray[i] = ray.cast<float>();
          rays.valid[i] = 1;
        }
      },
      8);
  return rays;
}

PlainPlanes findPlainPlanes(const PlainRays& rays, const Camera& camera0, const Eigen::Vector3d& tPrime, int width,
                            int height, const std::vector<float>& support, const PlainFillParams& p) {
  PlainPlanes out;
  const BuiltCamera cam(camera0);
  const std::vector<uint8_t> texture = texturePixels(support, p.noise);
  std::vector<int> label;
  const std::vector<std::vector<int>> regions = plainRegions(width, height, texture, label);
  out.labels.assign(label.size(), -1.f);
  const long long masked = std::count_if(texture.begin(), texture.end(), [](uint8_t t) { return t != kUnknown; });
  const size_t minPixels = size_t(std::max(16.0, p.minShare * double(masked)));
  std::vector<int> stamp(texture.size(), -1);
  for (int id = 0; id < int(regions.size()) && int(out.planes.size()) < kMaxPlainPlanes; ++id) {
    const std::vector<int>& region = regions[size_t(id)];
    if (region.size() < minPixels) continue;
    ++out.regions;
    const std::vector<int> border = borderOf(width, height, region, id, label, texture, p.supportRadius, stamp);
    const std::vector<Sample> samples = borderSamples(cam, tPrime, border, support, p.minSupportConfidence);
    PlaneFit fit = ransacPlane(samples, p.inlierPx, uint32_t(id));
    if (fit.inliers.size() < std::max<size_t>(8, size_t(p.minInliers * double(samples.size())))) continue;
    // How well the border fixes the plane: its covariance from the inliers' scatter, taken
    // as at least minScatter since neighbouring border pixels err alike.
    Eigen::Matrix3d normal;
    if (!fitPlane(samples, fit.inliers, fit.a, &normal)) continue;
    double scatter = 0;
    for (int k : fit.inliers) scatter += std::pow(residualPx(samples[size_t(k)], fit.a), 2);
    scatter = std::max(scatter / double(fit.inliers.size()), p.minScatter);
    const std::vector<int> known = filledPixels(cam, tPrime, region, rays, fit.a, scatter * normal.inverse(), p);
    if (known.empty()) continue;
    const float index = float(out.planes.size());
    out.planes.push_back(fit.a.cast<float>());
    for (int i : known) out.labels[size_t(i)] = index;
    out.pixels += (long long)known.size();
  }
  return out;
}

}  // namespace cs

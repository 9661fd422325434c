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
constexpr int kScored = 256;

enum Texture : uint8_t { kUnknown, kPlain, kTextured };

// Plain: the grey levels of the window around (Backend::plainSupport's variance) vary no
// more than twice the noise would make them (a noise-only window's spread is the noise
// itself). Textured: more than four times. Unknown: outside the mask, at its rim and in
// between.
std::vector<uint8_t> texturePixels(const std::vector<float>& support, float noise) {
  const float limit = 4.f * noise * noise;
  std::vector<uint8_t> texture(support.size() / kPlainSupportChannels, kUnknown);
  for (size_t i = 0; i < texture.size(); ++i) {
    const float variance = support[kPlainSupportChannels * i + kSupportVariance];
    if (variance >= 0.f) texture[i] = variance < limit ? kPlain : variance > 4.f * limit ? kTextured : kUnknown;
  }
  return texture;
}

// 4-connected regions of plain pixels, found breadth first: each pixel's region index (-1:
// none) in `label`; region k is order[start[k] .. start[k + 1]).
struct Regions {
  std::vector<int> order;
  std::vector<size_t> start{0};
  size_t size(int k) const { return start[size_t(k) + 1] - start[size_t(k)]; }
  std::vector<int> pixels(int k) const {
    return {order.begin() + ptrdiff_t(start[size_t(k)]), order.begin() + ptrdiff_t(start[size_t(k) + 1])};
  }
};

Regions plainRegions(int width, int height, const std::vector<uint8_t>& texture, std::vector<int>& label) {
  label.assign(texture.size(), -1);
  Regions regions;
  regions.order.reserve(texture.size());
  auto visit = [&](int j, int id) {
    if (texture[size_t(j)] != kPlain || label[size_t(j)] >= 0) return;
    label[size_t(j)] = id;
    regions.order.push_back(j);
  };
  for (int first = 0; first < int(texture.size()); ++first) {
    if (texture[size_t(first)] != kPlain || label[size_t(first)] >= 0) continue;
    const int id = int(regions.start.size()) - 1;
    visit(first, id);
    for (size_t head = regions.start.back(); head < regions.order.size(); ++head) {
      const int i = regions.order[head], x = i % width, y = i / width;
      if (x > 0) visit(i - 1, id);
      if (x + 1 < width) visit(i + 1, id);
      if (y > 0) visit(i - width, id);
      if (y + 1 < height) visit(i + width, id);
    }
    regions.start.push_back(regions.order.size());
  }
  return regions;
}

// A pixel's ray, inverse depth and how far (full-resolution px) its image moves per unit of
// inverse depth there: the scale that turns an inverse-depth residual into pixels.
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

// The textured pixels within `radius` of the region: its border, where the images had
// texture to match (each once, in index order).
std::vector<int> borderOf(int width, int height, const std::vector<int>& region, int id, const std::vector<int>& label,
                          const std::vector<uint8_t>& texture, int radius) {
  std::vector<int> border;
  for (int i : region) {
    const int x = i % width, y = i / width;
    const bool inner = x > 0 && y > 0 && x + 1 < width && y + 1 < height && label[size_t(i - 1)] == id &&
                       label[size_t(i + 1)] == id && label[size_t(i - width)] == id && label[size_t(i + width)] == id;
    if (inner) continue;
    for (int dy = -radius; dy <= radius; ++dy)
      for (int dx = -radius; dx <= radius; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if (nx >= 0 && ny >= 0 && nx < width && ny < height && texture[size_t(ny) * width + nx] == kTextured)
          border.push_back(ny * width + nx);
      }
  }
  std::sort(border.begin(), border.end());
  border.erase(std::unique(border.begin(), border.end()), border.end());
  return border;
}

struct PlaneFit {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();  // q = a . ray
  std::vector<int> inliers;
};

double residualPx(const Sample& s, const Eigen::Vector3d& a) { return std::abs(a.dot(s.ray) - s.q) * s.pxPerQ; }

std::vector<int> inliersOf(const std::vector<Sample>& samples, const Eigen::Vector3d& a, double inlierPx) {
  std::vector<int> inliers;
  for (int m = 0; m < int(samples.size()); ++m)
    if (residualPx(samples[size_t(m)], a) < inlierPx) inliers.push_back(m);
  return inliers;
}

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
// draws, scored on the pool in batches, the first best kept: every run fills alike), until
// enough triples were drawn that one of them, at the best plane's inlier share w, was all
// inliers with 99 % probability (log 0.01 / log(1 - w^3): 35 at w = 1/2), at most
// kRansacTrials; refined on its inliers. MSAC scoring: each sample costs its squared
// residual, capped at the inlier bound, so among planes with as many inliers the one they
// fit closer wins.
PlaneFit ransacPlane(const std::vector<Sample>& samples, double inlierPx, uint32_t seed) {
  constexpr int kBatch = 32;
  PlaneFit best;
  const int n = int(samples.size());
  if (n < 3) return best;
  // Triples are scored on at most kScored evenly spaced samples (the refit uses all).
  const int stride = (n + kScored - 1) / kScored, scored = (n + stride - 1) / stride;
  uint32_t state = seed * 2654435761u + 1u;
  auto draw = [&] {
    state = state * 1664525u + 1013904223u;
    return int((uint64_t(state >> 8) * uint64_t(n)) >> 24);
  };
  std::array<double, kBatch> costs;
  std::array<int, kBatch> inliers;
  std::array<Eigen::Vector3d, kBatch> planes;
  std::array<std::array<int, 3>, kBatch> triples;
  double bestCost = INFINITY;
  int bestInliers = 0;
  for (int drawn = 0; drawn < kRansacTrials;) {
    for (auto& t : triples) t = {draw(), draw(), draw()};
    detail::parallelFor(
        kBatch,
        [&](int b) {
          costs[size_t(b)] = INFINITY;
          const auto [i, j, k] = triples[size_t(b)];
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
          int count = 0;
          for (int m = 0; m < n; m += stride) {
            const double r = residualPx(samples[size_t(m)], a);
            cost += std::min(r * r, inlierPx * inlierPx);
            count += r < inlierPx;
          }
          costs[size_t(b)] = cost, inliers[size_t(b)] = count, planes[size_t(b)] = a;
        },
        4);
    for (int b = 0; b < kBatch; ++b)
      if (costs[size_t(b)] < bestCost) {
        bestCost = costs[size_t(b)], bestInliers = inliers[size_t(b)];
        best.a = planes[size_t(b)];
      }
    drawn += kBatch;
    const double share = double(bestInliers) / scored;
    if (share > 0 && drawn >= std::log(0.01) / std::log1p(-std::min(share * share * share, 0.999999))) break;
  }
  if (!std::isfinite(bestCost)) return best;
  best.inliers = inliersOf(samples, best.a, inlierPx);
  if (best.inliers.size() < 3 || !fitPlane(samples, best.inliers, best.a)) return PlaneFit{};
  best.inliers = inliersOf(samples, best.a, inlierPx);
  return best;
}

// The region's border samples: each voting support pixel's full-resolution ray, the inverse
// depth its warp triangulates to, and its pixels per unit of inverse depth; in fixed pieces
// on the pool, joined in order.
std::vector<Sample> borderSamples(const BuiltCamera& cam, const Eigen::Vector3d& tPrime, const std::vector<int>& border,
                                  const std::vector<float>& support, double minConfidence) {
  constexpr size_t kPiece = 64;
  std::vector<std::vector<Sample>> pieces((border.size() + kPiece - 1) / kPiece);
  detail::parallelPieces(border.size(), kPiece, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      const float* b = &support[kPlainSupportChannels * size_t(border[k])];
      if (!(b[kSupportConfidence] >= minConfidence)) continue;
      const Vec2<double> x(b[0], b[1]), w(b[2], b[3]);
      const double radial = triangulateRadial(cam, tPrime, x, w);
      Sample s;
      Vec3<double> ray;
      if (std::isnan(radial) || !cam.unproject(x, ray)) continue;
      s.ray = ray;
      s.q = std::isinf(radial) ? 0.0 : 1.0 / radial;
      if (pxPerInverseDepth(cam, tPrime, s.ray, s.q, s.pxPerQ)) pieces[begin / kPiece].push_back(s);
    }
  });
  std::vector<Sample> samples;
  for (const auto& p : pieces) samples.insert(samples.end(), p.begin(), p.end());
  return samples;
}

// The pixels of the region the plane fills, with the plane's confidence there: none when it
// lies behind a ray of the region or nearer than the nearest sphere (it is not the region's
// surface); else those where the border fixes it to maxDeviationPx (the rest, far from any
// border that voted, keep the solver's estimate). The deviation is in pixels of motion per
// unit of inverse depth at the ray (at infinity: a few percent from that at the plane's
// depth); the confidence has the structure term's form, 1 / (1 + (deviation / sigmaPx)^2).
// In fixed pieces on the pool, joined in order.
std::vector<std::pair<int, float>> filledPixels(const std::vector<int>& region, const PlainRays& rays,
                                                const Eigen::Vector3d& a, const Eigen::Matrix3d& covariance,
                                                const PlainFillParams& p) {
  constexpr size_t kPiece = 1024;
  const size_t pieces = (region.size() + kPiece - 1) / kPiece;
  std::vector<std::vector<std::pair<int, float>>> known(pieces);
  std::vector<uint8_t> behind(pieces, 0);
  detail::parallelPieces(region.size(), kPiece, [&](size_t begin, size_t end) {
    const size_t piece = begin / kPiece;
    for (size_t k = begin; k < end && !behind[piece]; ++k) {
      const int i = region[k];
      if (!rays.valid[size_t(i)]) continue;
      const Eigen::Vector3d ray = rays.ray[size_t(i)].cast<double>();
      const double q = a.dot(ray);
      if (!(q >= 0.0) || q > p.qMax) {
        behind[piece] = 1;
        break;
      }
      const double deviation = rays.pxPerQ[size_t(i)] * std::sqrt(ray.dot(covariance * ray));
      const double ratio = deviation / p.confidenceSigmaPx;
      if (deviation <= p.maxDeviationPx) known[piece].push_back({i, float(1.0 / (1.0 + ratio * ratio))});
    }
  });
  std::vector<std::pair<int, float>> all;
  for (size_t k = 0; k < pieces; ++k) {
    if (behind[k]) return {};
    all.insert(all.end(), known[k].begin(), known[k].end());
  }
  return all;
}

}  // namespace

PlainRays plainRays(const Camera& camera0, const Eigen::Vector3d& tPrime, int width, int height) {
  PlainRays rays;
  rays.ray.resize(size_t(width) * height);
  rays.pxPerQ.assign(rays.ray.size(), 0.f);
  rays.valid.assign(rays.ray.size(), 0);
  const BuiltCamera cam(camera0);
  const double sx = double(camera0.width) / width, sy = double(camera0.height) / height;
  detail::parallelFor(
      height,
      [&](int y) {
        for (int x = 0; x < width; ++x) {
          Vec3<double> ray;
          const size_t i = size_t(y) * width + x;
          double pxPerQ;
          if (!cam.unproject(Vec2<double>((x + 0.5) * sx - 0.5, (y + 0.5) * sy - 0.5), ray) ||
              !pxPerInverseDepth(cam, tPrime, ray, 0.0, pxPerQ))
            continue;
          rays.ray[i] = ray.cast<float>();
          rays.pxPerQ[i] = float(pxPerQ);
          rays.valid[i] = 1;
        }
      },
      8);
  return rays;
}

namespace {

// One region's plane and the pixels it fills (none: no plane).
struct RegionFill {
  Eigen::Vector3f a = Eigen::Vector3f::Zero();
  std::vector<std::pair<int, float>> pixels;  // and the plane's confidence there
};

RegionFill fillRegion(const BuiltCamera& cam, const Eigen::Vector3d& tPrime, const PlainRays& rays, int width,
                      int height, const std::vector<int>& region, int id, const std::vector<int>& label,
                      const std::vector<uint8_t>& texture, const std::vector<float>& support,
                      const PlainFillParams& p) {
  RegionFill out;
  const std::vector<int> border = borderOf(width, height, region, id, label, texture, p.supportRadius);
  const std::vector<Sample> samples = borderSamples(cam, tPrime, border, support, p.minSupportConfidence);
  PlaneFit fit = ransacPlane(samples, p.inlierPx, uint32_t(id));
  if (fit.inliers.size() < std::max<size_t>(8, size_t(p.minInliers * double(samples.size())))) return out;
  // How well the border fixes the plane: its covariance from the inliers' scatter, taken as
  // at least minScatter since neighbouring border pixels err alike.
  Eigen::Matrix3d normal;
  if (!fitPlane(samples, fit.inliers, fit.a, &normal)) return out;
  double scatter = 0;
  for (int k : fit.inliers) scatter += std::pow(residualPx(samples[size_t(k)], fit.a), 2);
  scatter = std::max(scatter / double(fit.inliers.size()), p.minScatter);
  out.pixels = filledPixels(region, rays, fit.a, scatter * normal.inverse(), p);
  out.a = fit.a.cast<float>();
  return out;
}

}  // namespace

// The regions are fitted on the pool, one a worker (a region's own loops then run on it
// alone: one dispatch a frame rather than several a region), and numbered in order.
PlainPlanes findPlainPlanes(const PlainRays& rays, const Camera& camera0, const Eigen::Vector3d& tPrime, int width,
                            int height, const std::vector<float>& support, const PlainFillParams& p) {
  PlainPlanes out;
  const BuiltCamera cam(camera0);
  const std::vector<uint8_t> texture = texturePixels(support, p.noise);
  std::vector<int> label;
  const Regions regions = plainRegions(width, height, texture, label);
  out.labels.assign(2 * label.size(), 0.f);
  for (size_t i = 0; i < label.size(); ++i) out.labels[2 * i] = -1.f;
  const long long masked = std::count_if(texture.begin(), texture.end(), [](uint8_t t) { return t != kUnknown; });
  const size_t minPixels = size_t(std::max(16.0, p.minShare * double(masked)));
  std::vector<int> large;
  for (int id = 0; id + 1 < int(regions.start.size()); ++id)
    if (regions.size(id) >= minPixels) large.push_back(id);
  out.regions = int(large.size());
  std::vector<RegionFill> fills(large.size());
  detail::parallelFor(int(large.size()), [&](int k) {
    const int id = large[size_t(k)];
    fills[size_t(k)] = fillRegion(cam, tPrime, rays, width, height, regions.pixels(id), id, label, texture, support, p);
  });
  for (const RegionFill& f : fills) {
    if (f.pixels.empty() || int(out.planes.size()) == kMaxPlainPlanes) continue;
    const float index = float(out.planes.size());
    out.planes.push_back(f.a);
    for (const auto& [i, confidence] : f.pixels) {
      out.labels[2 * size_t(i)] = index;
      out.labels[2 * size_t(i) + 1] = confidence;
    }
    out.pixels += (long long)f.pixels.size();
  }
  return out;
}

}  // namespace cs

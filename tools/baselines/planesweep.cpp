#include "baselines/planesweep.hpp"
#include "baselines/methods.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <thread>
#include <vector>

namespace cs::baselines {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kBad = 1e9f;  // cost of a hypothesis that cannot be scored
constexpr double kPi = 3.14159265358979323846;

float bilinear(const ImageF& img, float x, float y) {
  const int x0 = std::min(std::max(int(std::floor(x)), 0), img.width - 2);
  const int y0 = std::min(std::max(int(std::floor(y)), 0), img.height - 2);
  const float fx = std::min(std::max(x - float(x0), 0.f), 1.f), fy = std::min(std::max(y - float(y0), 0.f), 1.f);
  const float* r0 = &img.data[size_t(y0) * img.width + x0];
  const float* r1 = r0 + img.width;
  return (1 - fy) * ((1 - fx) * r0[0] + fx * r0[1]) + fy * ((1 - fx) * r1[0] + fx * r1[1]);
}

// Per-pixel state of the streaming winner-take-all (no cost volume is stored).
struct Track {
  float best = kBad, before = kBad, after = kBad;  // winner and its two neighbours' costs
  float second = kBad;                             // best cost not adjacent to the winner
  float last = kBad;                               // cost at k - 1
  float minTo1 = kBad, minTo2 = kBad;              // min cost over 0..k-1 and 0..k-2
  int k = -1;
};

int threadCount(int requested) {
  int n = requested > 0 ? requested : int(std::thread::hardware_concurrency());
  return std::max(1, n);
}

// Runs fn(y0, y1) over bands of rows on n threads.
template <class Fn>
void parallelBands(int height, int threads, int band, Fn fn) {
  std::atomic<int> next{0};
  auto worker = [&]() {
    for (;;) {
      const int y0 = next.fetch_add(band);
      if (y0 >= height) return;
      fn(y0, std::min(height, y0 + band));
    }
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < threads; ++i) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

}  // namespace

ImageF downsample(const ImageF& img, double scale) {
  ImageF cur = img;
  for (double s = 1.0; s > scale * 1.0001; s *= 0.5) {
    ImageF half(std::max(1, (cur.width + 1) / 2), std::max(1, (cur.height + 1) / 2));
    for (int y = 0; y < half.height; ++y)
      for (int x = 0; x < half.width; ++x) {
        const int xa = std::min(2 * x, cur.width - 1), xb = std::min(2 * x + 1, cur.width - 1);
        const int ya = std::min(2 * y, cur.height - 1), yb = std::min(2 * y + 1, cur.height - 1);
        half(x, y) = 0.25f * (cur(xa, ya) + cur(xb, ya) + cur(xa, yb) + cur(xb, yb));
      }
    cur = std::move(half);
  }
  return cur;
}

Rig swapRig(const Rig& rig) {
  Rig s;
  s.cam0 = rig.cam1;
  s.cam1 = rig.cam0;
  s.R = rig.R.transpose();
  s.t = -rig.R.transpose() * rig.t;
  return s;
}

SweepResult planeSweep(const Rig& rig, const ImageF& img0Full, const ImageF& img1Full, const SweepParams& p) {
  if (p.window < 3 || p.window % 2 == 0) throw Error("plane sweep: the window must be odd and >= 3");
  if (!(p.minDepth > 0)) throw Error("plane sweep: minDepth must be positive");
  if (!(p.scale > 0 && p.scale <= 1)) throw Error("plane sweep: scale must be in (0, 1]");
  const ImageF img0 = downsample(img0Full, p.scale), img1 = downsample(img1Full, p.scale);
  const double s = double(img0.width) / img0Full.width;
  const BuiltCamera cam0(rig.cam0.scaled(s)), cam1(rig.cam1.scaled(s));
  const int W = img0.width, H = img0.height, r = p.window / 2;
  const float n = float(p.window * p.window);

  SweepResult out;
  out.cam = cam0.camera();
  out.qMax = 1.0 / p.minDepth;
  const Eigen::Matrix3d R = rig.R;
  const Eigen::Vector3d t = rig.t;

  // Rays of camera 0 rotated into camera 1 (R d0); the hypothesis q = 1/rho projects
  // R d0 + q t (X1 = (R d0 + q t) / q). Pixels outside the used field of view: invalid.
  const double cosMax = std::cos(std::min(0.5 * p.maxFovDeg, 179.9) * kPi / 180.0);
  std::vector<Eigen::Vector3d> rays(size_t(W) * H);
  std::vector<uint8_t> valid0(size_t(W) * H, 0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      Vec3<double> d;
      if (!cam0.unproject(Vec2<double>(x, y), d) || d.z() < cosMax || !cam0.inImage(Vec2<double>(x, y))) continue;
      rays[size_t(y) * W + x] = R * d;
      valid0[size_t(y) * W + x] = 1;
    }

  // Number of hypotheses: neighbouring spheres move no pixel by more than pxPerPlane.
  int K = p.planes;
  if (K <= 0) {
    double maxMove = 0;
    for (int y = 0; y < H; y += 4)
      for (int x = 0; x < W; x += 4) {
        if (!valid0[size_t(y) * W + x]) continue;
        const Eigen::Vector3d& d = rays[size_t(y) * W + x];
        Vec2<double> a, b;
        if (cam1.project(Vec3<double>(d), a) && cam1.project(Vec3<double>(d + out.qMax * t), b) && cam1.inImage(a))
          maxMove = std::max(maxMove, (a - b).norm());
      }
    K = std::min(2048, std::max(16, int(std::ceil(maxMove / p.pxPerPlane)) + 1));
  }
  out.planes = K;

  // Window statistics of image 0 (mean, variance), invalid where the window leaves the
  // used region.
  std::vector<float> mean0(size_t(W) * H, 0.f), var0(size_t(W) * H, -1.f);
  for (int y = r; y < H - r; ++y)
    for (int x = r; x < W - r; ++x) {
      double s1 = 0, s2 = 0;
      bool ok = true;
      for (int j = -r; j <= r && ok; ++j)
        for (int i = -r; i <= r; ++i) {
          const size_t idx = size_t(y + j) * W + (x + i);
          if (!valid0[idx]) {
            ok = false;
            break;
          }
          s1 += img0.data[idx];
          s2 += double(img0.data[idx]) * img0.data[idx];
        }
      if (!ok) continue;
      const double m = s1 / n;
      mean0[size_t(y) * W + x] = float(m);
      var0[size_t(y) * W + x] = float(std::max(0.0, s2 / n - m * m));
    }
  // Regularises the ZNCC of nearly flat windows (about one grey level of noise).
  const float eps = 1e-5f;

  std::vector<Track> track(size_t(W) * H);
  const int threads = threadCount(p.threads);
  const int band = std::max(8, H / (4 * threads));
  parallelBands(H, threads, band, [&](int y0, int y1) {
    const int ya = std::max(0, y0 - r), yb = std::min(H, y1 + r);
    const int rows = yb - ya;
    std::vector<float> warped(size_t(W) * rows), ok(size_t(W) * rows);
    std::vector<float> h1(size_t(W) * rows), h11(size_t(W) * rows), h01(size_t(W) * rows), hok(size_t(W) * rows);
    std::vector<float> c1(W), c11(W), c01(W), cok(W);
    for (int k = 0; k < K; ++k) {
      const double q = out.qMax * double(k) / double(K - 1);
      // 1. Image 1 resampled on hypothesis k for the band (and its window margin).
      for (int y = ya; y < yb; ++y)
        for (int x = 0; x < W; ++x) {
          const size_t idx = size_t(y) * W + x, b = size_t(y - ya) * W + x;
          warped[b] = 0.f;
          ok[b] = 0.f;
          if (!valid0[idx]) continue;
          Vec2<double> px;
          if (!cam1.project(Vec3<double>(rays[idx] + q * t), px) || !cam1.inImage(px, 0.5)) continue;
          warped[b] = bilinear(img1, float(px.x()), float(px.y()));
          ok[b] = 1.f;
        }
      // 2. Horizontal window sums of I1, I1^2, I0 I1 and the valid count.
      for (int y = ya; y < yb; ++y) {
        const size_t b = size_t(y - ya) * W;
        const float* i0 = &img0.data[size_t(y) * W];
        float a1 = 0, a11 = 0, a01 = 0, aok = 0;
        for (int x = 0; x < W + r; ++x) {
          if (x < W) {
            const float v = warped[b + x];
            a1 += v, a11 += v * v, a01 += i0[x] * v, aok += ok[b + x];
          }
          if (x - 2 * r - 1 >= 0) {
            const int o = x - 2 * r - 1;
            const float v = warped[b + o];
            a1 -= v, a11 -= v * v, a01 -= i0[o] * v, aok -= ok[b + o];
          }
          if (x - r >= 0) h1[b + x - r] = a1, h11[b + x - r] = a11, h01[b + x - r] = a01, hok[b + x - r] = aok;
        }
      }
      // 3. Vertical sums per output row, then ZNCC and the streaming winner-take-all.
      for (int y = y0; y < y1; ++y) {
        if (y - r < 0 || y + r >= H) continue;
        std::fill(c1.begin(), c1.end(), 0.f);
        std::fill(c11.begin(), c11.end(), 0.f);
        std::fill(c01.begin(), c01.end(), 0.f);
        std::fill(cok.begin(), cok.end(), 0.f);
        for (int j = y - r; j <= y + r; ++j) {
          const size_t b = size_t(j - ya) * W;
          for (int x = 0; x < W; ++x)
            c1[x] += h1[b + x], c11[x] += h11[b + x], c01[x] += h01[b + x], cok[x] += hok[b + x];
        }
        for (int x = r; x < W - r; ++x) {
          const size_t idx = size_t(y) * W + x;
          const float v0 = var0[idx];
          if (v0 < 0) continue;
          float cost = kBad;
          if (cok[x] > n - 0.5f) {
            const float m1 = c1[x] / n;
            const float v1 = std::max(0.f, c11[x] / n - m1 * m1);
            const float cov = c01[x] / n - mean0[idx] * m1;
            cost = 1.f - cov / std::sqrt((v0 + eps) * (v1 + eps));
          }
          Track& tr = track[idx];
          if (cost < tr.best) {
            tr.second = tr.minTo2;  // exactly the costs 0..k-2 are not adjacent to k
            tr.best = cost, tr.k = k, tr.before = tr.last, tr.after = kBad;
          } else {
            if (k == tr.k + 1)
              tr.after = cost;
            else
              tr.second = std::min(tr.second, cost);
          }
          tr.minTo2 = tr.minTo1;
          tr.minTo1 = std::min(tr.minTo1, cost);
          tr.last = cost;
        }
      }
    }
  });

  out.invDepth = ImageF(W, H, kNaN);
  out.cost = ImageF(W, H, kNaN);
  out.distinct = ImageF(W, H, kNaN);
  const double step = out.qMax / double(K - 1);
  for (size_t i = 0; i < track.size(); ++i) {
    const Track& tr = track[i];
    if (tr.k < 0 || tr.best >= kBad) continue;
    double offset = 0;
    if (tr.before < kBad && tr.after < kBad) {
      const double den = double(tr.before) - 2.0 * tr.best + tr.after;
      if (den > 1e-12) offset = std::min(0.5, std::max(-0.5, 0.5 * (double(tr.before) - tr.after) / den));
    }
    out.invDepth.data[i] = float(std::max(0.0, (tr.k + offset) * step));
    out.cost.data[i] = tr.best;
    out.distinct.data[i] = tr.second < kBad ? tr.second - tr.best : 2.f;
  }
  return out;
}

ImageU8 leftRightCheck(const Rig& rig, const SweepResult& ref, const SweepResult& other, double tolPx) {
  const BuiltCamera c0(ref.cam), c1(other.cam);
  ImageU8 ok(ref.cam.width, ref.cam.height, 0);
  for (int y = 0; y < ref.cam.height; ++y)
    for (int x = 0; x < ref.cam.width; ++x) {
      const float q = ref.invDepth(x, y);
      if (std::isnan(q)) continue;
      Vec3<double> d0;
      if (!c0.unproject(Vec2<double>(x, y), d0)) continue;
      // X1 ~ R d0 + q t (scaled by 1/q, which projection ignores).
      Vec2<double> x1;
      if (!c1.project(Vec3<double>(rig.R * d0 + double(q) * rig.t), x1) || !c1.inImage(x1)) continue;
      const int xi = int(std::lround(x1.x())), yi = int(std::lround(x1.y()));
      if (!other.invDepth.inside(xi, yi)) continue;
      const float q1 = other.invDepth(xi, yi);
      Vec3<double> d1;
      if (std::isnan(q1) || !c1.unproject(x1, d1)) continue;
      // Back to camera 0: X0 ~ R^T (d1 - q1 t).
      Vec2<double> back;
      if (!c0.project(Vec3<double>(rig.R.transpose() * (d1 - double(q1) * rig.t)), back)) continue;
      if ((back - Vec2<double>(x, y)).norm() <= tolPx) ok(x, y) = 1;
    }
  return ok;
}

ImageF upsampleDepth(const SweepResult& r, const Camera& full, const ImageU8* mask) {
  ImageF q = r.invDepth;
  if (mask)
    for (size_t i = 0; i < q.size(); ++i)
      if (!mask->data[i]) q.data[i] = kNaN;
  const double s = double(r.cam.width) / full.width;
  ImageF out(full.width, full.height, kNaN);
  for (int y = 0; y < full.height; ++y)
    for (int x = 0; x < full.width; ++x) {
      const float v = sampleBilinear(q, (x + 0.5) * s - 0.5, (y + 0.5) * s - 0.5);
      if (std::isnan(v)) continue;
      out(x, y) = v > 0 ? 1.f / v : std::numeric_limits<float>::infinity();
    }
  return out;
}

}  // namespace cs::baselines

// ---- planesweep / planesweep-valid ----
#include <chrono>

namespace cs::baselines {

void runPlaneSweep(const Rig& rig, const ImageF& left, const ImageF& right, const PlaneSweepOptions& o,
                   MethodResult& all, MethodResult& valid) {
  auto start = std::chrono::steady_clock::now();
  const SweepResult ref = planeSweep(rig, left, right, o.sweep);
  all = resultFromDepth(rig, upsampleDepth(ref, rig.cam0));
  all.ms = msSince(start);
  const Rig swapped = swapRig(rig);
  const SweepResult other = planeSweep(swapped, right, left, o.sweep);
  ImageU8 keep = leftRightCheck(rig, ref, other, o.lrTolPx);
  for (size_t i = 0; i < keep.size(); ++i)
    if (!(ref.cost.data[i] <= o.maxCost) || !(ref.distinct.data[i] >= o.minDistinct)) keep.data[i] = 0;
  valid = resultFromDepth(rig, upsampleDepth(ref, rig.cam0, &keep));
  valid.ms = msSince(start);
}

}  // namespace cs::baselines

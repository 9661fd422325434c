// The discrete operators of the solver: adjointness of grad/div on a masked disc, the
// data-term prox, and the preconditioner.
#include <cmath>
#include <cstdint>
#include <vector>

#include "cpu_backend.hpp"
#include "golden_cases.hpp"
#include "operators.hpp"
#include "test_util.hpp"

using namespace cs::cpu;

namespace {

// Deterministic pseudo-random values in [-1, 1].
float hashNoise(uint32_t i) { return 2.f * cs::golden::hash01(i) - 1.f; }

struct Grid {
  int w, h, c;
  std::vector<float> data;
  Grid(int w_, int h_, int c_, uint32_t seed) : w(w_), h(h_), c(c_), data(size_t(w_) * h_ * c_) {
    for (size_t i = 0; i < data.size(); ++i) data[i] = hashNoise(uint32_t(i) * 2654435761U + seed);
  }
  View view() { return View{data.data(), w, h, c}; }
};

// A disc of radius r inside a w x h grid, plus an isolated pixel and a hole.
Grid discMask(int w, int h, float r) {
  Grid m(w, h, 1, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) m.data[size_t(y) * w + x] = std::hypot(x - 0.5f * w, y - 0.5f * h) <= r ? 1.f : 0.f;
  m.data[size_t(h / 2) * w + w / 2] = 0.f;  // a hole in the middle
  m.data[0] = 1.f;                          // an isolated pixel in the corner
  return m;
}

}  // namespace

TEST_CASE("grad and div are adjoint on a masked disc: <grad u, p> = -<u, div p>") {
  for (auto [w, h] : {std::pair{31, 23}, std::pair{17, 40}}) {
    Grid mask = discMask(w, h, 0.4f * std::min(w, h)), u(w, h, 1, 1), p(w, h, 2, 2);
    View m = mask.view(), uv = u.view(), pv = p.view();
    double lhs = 0, rhs = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        lhs += double(gradX(uv, m, x, y)) * pv.at(x, y, 0) + double(gradY(uv, m, x, y)) * pv.at(x, y, 1);
        auto px = [&](int i, int j) { return pv.at(i, j, 0); };
        auto py = [&](int i, int j) { return pv.at(i, j, 1); };
        rhs -= double(uv.at(x, y)) * divergence(m, x, y, px, py);
      }
    CHECK(std::abs(lhs) > 1.0);  // the test would be empty otherwise
    CHECK(lhs == doctest::Approx(rhs).epsilon(1e-5));
  }
}

TEST_CASE("gradient is zero across the mask border and the image border") {
  Grid mask = discMask(15, 15, 5.f), u(15, 15, 1, 3);
  View m = mask.view(), uv = u.view();
  for (int y = 0; y < 15; ++y)
    for (int x = 0; x < 15; ++x) {
      if (!masked(m, x, y) || !masked(m, x + 1, y)) CHECK(gradX(uv, m, x, y) == 0.f);
      if (!masked(m, x, y) || !masked(m, x, y + 1)) CHECK(gradY(uv, m, x, y) == 0.f);
    }
}

TEST_CASE("data prox minimises (u - uHat)^2 / (2 tau) + lambda |iz + (u - u0) iu|") {
  for (uint32_t i = 0; i < 200; ++i) {
    float uHat = 3.f * hashNoise(i), u0 = hashNoise(i + 1000), iu = 0.3f * hashNoise(i + 2000),
          iz = 0.2f * hashNoise(i + 3000), tau = 0.05f + std::abs(hashNoise(i + 4000)), lambda = 20.f;
    auto energy = [&](double u) { return (u - uHat) * (u - uHat) / (2 * tau) + lambda * std::abs(iz + (u - u0) * iu); };
    float u = dataProx(uHat, u0, iu, iz, tau * lambda);
    // No point of a fine grid around the answer does better.
    for (double d = -2; d <= 2; d += 1e-3) CHECK(energy(u) <= energy(u + d) + 1e-5);
  }
  CHECK(dataProx(0.7f, 0.f, 0.f, 0.3f, 1.f) == 0.7f);  // no gradient: no data term
}

TEST_CASE("preconditioned steps are positive and finite on a masked disc") {
  const int w = 29, h = 21;
  Grid mask = discMask(w, h, 9.f), image(w, h, 1, 5), tensor(w, h, 4, 0), steps(w, h, 4, 0);
  structureTensor(tensor.view(), steps.view(), image.view(), mask.view(), {9.f, 0.85f, 1e-4f, 1.f, 17.f, 1.2f});
  for (float s : steps.data) {
    CHECK(std::isfinite(s));
    CHECK(s > 0.f);
  }
  // D is symmetric positive definite with eigenvalues in [wMin, 1].
  for (int i = 0; i < w * h; ++i) {
    float a = tensor.data[4 * i], b = tensor.data[4 * i + 1], c = tensor.data[4 * i + 2];
    float tr = a + c, det = a * c - b * b;
    CHECK(det > 0.f);
    CHECK(tr <= 2.f + 1e-5f);
  }
}

TEST_CASE("primal-dual recovers a constant disparity from a consistent data term") {
  // rho(u) = iz + (u - u0) iu vanishes at u = 0.7 for every pixel: the TGV minimiser is
  // that constant, whatever the image structure.
  const int w = 33, h = 27;
  Grid mask = discMask(w, h, 12.f), image(w, h, 1, 11), tensor(w, h, 4, 0), steps(w, h, 4, 0);
  structureTensor(tensor.view(), steps.view(), image.view(), mask.view(), {9.f, 0.85f, 1e-4f, 1.f, 17.f, 1.2f});
  Grid u(w, h, 1, 0), uBar(w, h, 1, 0), v(w, h, 2, 0), vBar(w, h, 2, 0), p(w, h, 2, 0), q(w, h, 4, 0);
  Grid u0(w, h, 1, 0), iu(w, h, 1, 21), iz(w, h, 1, 0);
  for (auto* g : {&u, &uBar, &v, &vBar, &p, &q, &u0}) std::fill(g->data.begin(), g->data.end(), 0.f);
  for (size_t i = 0; i < iu.data.size(); ++i) {
    iu.data[i] = 0.05f + 0.1f * std::abs(iu.data[i]);
    iz.data[i] = -0.7f * iu.data[i];
  }
  cs::PrimalDualParams prm{20.f, 17.f, 1.2f, std::vector<cs::PrimalDualStep>(400, {1.f, 1.f, 1.f})};
  primalDual(u.view(), uBar.view(), v.view(), vBar.view(), p.view(), q.view(), u0.view(), iu.view(), iz.view(),
             tensor.view(), steps.view(), mask.view(), prm);
  View m = mask.view();
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (masked(m, x, y)) CHECK(u.view().at(x, y) == doctest::Approx(0.7f).epsilon(1e-3));
}

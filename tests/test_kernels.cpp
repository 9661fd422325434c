// Properties of the CPU oracle's resampling and bookkeeping kernels.
#include <cmath>
#include <vector>

#include "cpu_backend.hpp"
#include "test_util.hpp"

using namespace cs::cpu;

namespace {

struct Grid {
  int w, h, c;
  std::vector<float> data;
  Grid(int w_, int h_, int c_, float v = 0.f) : w(w_), h(h_), c(c_), data(size_t(w_) * h_ * c_, v) {}
  View view() { return View{data.data(), w, h, c}; }
  float& at(int x, int y, int ch = 0) { return data[(size_t(y) * w + x) * c + ch]; }
};

}  // namespace

TEST_CASE("warp by a constant flow shifts a linear ramp exactly (inside the image)") {
  Grid src(23, 17, 1), flow(23, 17, 2), dst(23, 17, 1);
  for (int y = 0; y < 17; ++y)
    for (int x = 0; x < 23; ++x) {
      src.at(x, y) = 0.1f * x + 0.03f * y;
      flow.at(x, y, 0) = 1.25f;
      flow.at(x, y, 1) = -0.5f;
    }
  warp(dst.view(), src.view(), flow.view());
  for (int y = 1; y < 17; ++y)
    for (int x = 0; x < 21; ++x)
      CHECK(dst.at(x, y) == doctest::Approx(0.1f * (x + 1.25f) + 0.03f * (y - 0.5f)).epsilon(1e-5));
  // Beyond the edge the sample clamps to the border value.
  CHECK(dst.at(22, 5) == doctest::Approx(src.at(22, 5) - 0.03f * 0.5f).epsilon(1e-5));
}

TEST_CASE("downsample keeps constants and the mean of a ramp; upsample scales values") {
  Grid src(41, 31, 1), dst(21, 16, 1), constant(41, 31, 1, 0.375f), cdst(21, 16, 1);
  for (int y = 0; y < 31; ++y)
    for (int x = 0; x < 41; ++x) src.at(x, y) = 0.02f * x;
  downsample(dst.view(), src.view(), 2.f);
  downsample(cdst.view(), constant.view(), 2.f);
  for (float v : cdst.data) CHECK(v == doctest::Approx(0.375f).epsilon(1e-6));
  // Away from the border the coarse pixel x sits at fine coordinate 2x + 0.5.
  for (int x = 2; x < 18; ++x) CHECK(dst.at(x, 8) == doctest::Approx(0.02f * (2 * x + 0.5f)).epsilon(1e-4));

  Grid coarse(11, 9, 2), fine(22, 18, 2);
  for (int y = 0; y < 9; ++y)
    for (int x = 0; x < 11; ++x) coarse.at(x, y, 0) = coarse.at(x, y, 1) = float(x);
  upsample(fine.view(), coarse.view(), 2.f, 2.f);
  for (int x = 2; x < 19; ++x)
    CHECK(fine.at(x, 4, 1) == doctest::Approx(2.f * ((x + 0.5f) / 2.f - 0.5f)).epsilon(1e-5));
}

TEST_CASE("upsampleEstimate: across a depth step each pixel takes the side its images match, never a blend") {
  // Fine disparity 2 left of column 20, 6 from it on, displacement along x; image 1 is
  // image 0 moved by it (a texture with no flat stretch), the coarse estimate that step.
  const int W = 40, H = 12, CW = 20, CH = 6;
  Grid n0(W, H, 1), n1(W, H, 1, 0.5f), mask(W, H, 1, 1.f), u(W, H, 1), w(W, H, 2);
  Grid coarseU(CW, CH, 1), coarseW(CW, CH, 2);
  auto truth = [](int x) { return x < 20 ? 2.f : 6.f; };
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) n0.at(x, y) = std::sin(1.7f * float(x) + 0.9f * float(y)) + 0.3f * std::cos(0.7f * x);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (x + int(truth(x)) < W) n1.at(x + int(truth(x)), y) = n0.at(x, y);
  for (int y = 0; y < CH; ++y)
    for (int x = 0; x < CW; ++x) coarseU.at(x, y) = coarseW.at(x, y, 0) = 0.5f * truth(2 * x);
  upsampleEstimate(u.view(), w.view(), coarseU.view(), coarseW.view(), n0.view(), n1.view(), mask.view(),
                   {2.f, 1.f, 2});
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      INFO("x = " << x << ", y = " << y);
      if (x >= 17 && x <= 22) {
        // Bilinear resampling would give 3 and 5 at x = 19, 20; here one side or the other.
        CHECK((u.at(x, y) == 2.f || u.at(x, y) == 6.f));
        CHECK(w.at(x, y, 0) == u.at(x, y));
        if (y >= 2 && y < H - 2) CHECK(u.at(x, y) == truth(x));  // the window sees the right side
      } else {
        CHECK(u.at(x, y) == truth(x));  // away from the step: bilinear of a constant
      }
    }
}

TEST_CASE("median removes an isolated spike and respects the mask") {
  Grid u(9, 9, 1, 1.f), mask(9, 9, 1, 1.f), out(9, 9, 1);
  u.at(4, 4) = 50.f;
  mask.at(0, 0) = 0.f;
  u.at(0, 0) = -7.f;
  median(out.view(), u.view(), mask.view());
  CHECK(out.at(4, 4) == 1.f);
  CHECK(out.at(0, 0) == -7.f);  // unmasked pixels are copied
  CHECK(out.at(1, 1) == 1.f);   // the unmasked neighbour's value is not used
}

TEST_CASE("accumulate clamps the increment and advances w along the tangent") {
  Grid u(3, 1, 1), u0(3, 1, 1), w(3, 1, 2), g(3, 1, 2), mask(3, 1, 1, 1.f);
  u.data = {0.5f, -0.05f, 3.f};
  u0.data = {0.f, 0.f, 0.f};
  g.data = {0.6f, 0.8f, 1.f, 0.f, 0.f, 1.f};
  mask.data[2] = 0.f;
  accumulate(u.view(), w.view(), u0.view(), g.view(), mask.view(), 0.2f);
  CHECK(u.data[0] == doctest::Approx(0.2f));
  CHECK(w.data[0] == doctest::Approx(0.12f));
  CHECK(w.data[1] == doctest::Approx(0.16f));
  CHECK(u.data[1] == doctest::Approx(-0.05f));
  CHECK(w.data[2] == doctest::Approx(-0.05f));
  CHECK(u.data[2] == 3.f);  // outside the mask nothing changes
  CHECK(w.data[5] == 0.f);
}

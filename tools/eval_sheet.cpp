// `eval --maps DIR`: per pair a sheet of pictures (the input over the ground truth, then
// each method's depth over its error in the paper's error bins) and each method's own
// error and depth pictures.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "baselines/draw.hpp"
#include "common.hpp"
#include "curvestereo/image_io.hpp"
#include "eval.hpp"

namespace cs::cli::eval {

namespace {

namespace fs = std::filesystem;
using baselines::RgbImage;

// The paper's error bins (px): 0, 0.19, 0.75, 3, 24, 48, inf; blue (good) to red (bad).
const float kErrorEdges[] = {0.19f, 0.75f, 3.f, 24.f, 48.f};
const uint32_t kErrorColours[] = {0x313695, 0x74add1, 0xfee090, 0xf46d43, 0xd73027, 0xa50026};

Image<uint32_t> errorPicture(const ImageF& error) {
  Image<uint32_t> out(error.width, error.height, 0);
  for (size_t i = 0; i < error.size(); ++i) {
    float e = error.data[i];
    if (std::isnan(e)) continue;
    int bin = 0;
    while (bin < 5 && e > kErrorEdges[bin]) ++bin;
    out.data[i] = kErrorColours[bin];
  }
  return out;
}

// Inverse depth on one colour scale (the ground truth's 2nd / 98th percentiles), so that
// every method's picture on a sheet is comparable.
struct DepthScale {
  float lo = 0, hi = 1;
};
DepthScale depthScale(const ImageF& gt) {
  std::vector<float> v;
  for (float d : gt.data)
    if (d > 0 && std::isfinite(d)) v.push_back(1.f / d);
  DepthScale s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.lo = 0.f;  // infinity (sky) at the cold end
  s.hi = v[size_t(0.98 * double(v.size() - 1))];
  return s;
}
Image<uint32_t> depthPicture(const ImageF& depth, const DepthScale& s) {
  ImageF inv(depth.width, depth.height, NAN);
  for (size_t i = 0; i < inv.size(); ++i) {
    const float d = depth.data[i];
    if (d > 0) inv.data[i] = std::isinf(d) ? 0.f : 1.f / d;
  }
  return colorizeScalar(inv, s.lo, s.hi);
}
Image<uint32_t> grayPicture(const ImageF& img) {
  Image<uint32_t> out(img.width, img.height);
  for (size_t i = 0; i < img.size(); ++i) {
    const uint32_t g = uint32_t(std::lround(255.f * std::min(1.f, std::max(0.f, img.data[i]))));
    out.data[i] = (g << 16) | (g << 8) | g;
  }
  return out;
}

}  // namespace

void writeSheet(const std::string& maps, const Pair& p, const std::vector<SheetEntry>& entries) {
  fs::create_directories(maps);
  const DepthScale scale = depthScale(p.depthLeft);
  // Sheet: column 0 = input over ground truth; then per method its depth over its error.
  const int shrink = p.left.width > 500 ? 2 : 1;
  const int tw = p.left.width / shrink, th = p.left.height / shrink, label = 24, gap = 6;
  const int cols = 1 + int(entries.size());
  baselines::Canvas sheet(cols * (tw + gap) + gap, 2 * (th + label + gap) + gap + 40, 0xffffff);
  auto tile = [&](int c, int r, const RgbImage& img, const std::string& text) {
    const int x = gap + c * (tw + gap), y = gap + r * (th + label + gap);
    sheet.text(x, y + 3, text, 0x202020, 2);
    sheet.blit(img, x, y + label, shrink);
  };
  ImageF gtShown = p.depthLeft;
  for (float& d : gtShown.data)
    if (d <= 0) d = NAN;
  tile(0, 0, grayPicture(p.left), p.name);
  tile(0, 1, depthPicture(gtShown, scale), "ground truth");
  char buf[96];
  for (size_t i = 0; i < entries.size(); ++i) {
    const SheetEntry& e = entries[i];
    tile(int(i) + 1, 0, depthPicture(*e.depth, scale), e.method);
    std::snprintf(buf, sizeof buf, "t>1 %.1f%% t>3 %.1f%%", e.tau1, e.tau3);
    tile(int(i) + 1, 1, errorPicture(*e.error), buf);
    writePngRgb((fs::path(maps) / (p.name + "_" + e.method + "_error.png")).string(), errorPicture(*e.error));
    writeDepthPng((fs::path(maps) / (p.name + "_" + e.method + "_depth.png")).string(), *e.depth);
  }
  // Legend of the error bins.
  const char* names[] = {"<0.19", "<0.75", "<3", "<24", "<48", ">48 or missing"};
  int x = gap;
  const int y = sheet.img.height - 30;
  for (int b = 0; b < 6; ++b) {
    sheet.fillRect(x, y, 20, 20, kErrorColours[b]);
    x += 26 + sheet.text(x + 26, y + 3, names[b], 0x202020, 2) + 20;
  }
  sheet.text(x + 20, y + 3, "px (black: not evaluated)   depth: inverse, common scale", 0x202020, 2);
  writePngRgb((fs::path(maps) / (p.name + "_sheet.png")).string(), sheet.img);
}

}  // namespace cs::cli::eval

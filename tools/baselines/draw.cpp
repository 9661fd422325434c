#include "baselines/draw.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace cs::baselines {

namespace {

// 5x7 glyphs, one byte per row, bit 4 = leftmost column.
struct Glyph {
  char c;
  uint8_t rows[7];
};
const Glyph kFont[] = {
    {' ', {0, 0, 0, 0, 0, 0, 0}},
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},
    {'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
    {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}},
    {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
    {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},
    {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},
    {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},
    {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},
    {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}},
    {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'>', {0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08}},
    {'<', {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},
    {'*', {0x00, 0x04, 0x15, 0x0E, 0x15, 0x04, 0x00}},
};

const uint8_t* glyph(char c) {
  if (c >= 'a' && c <= 'z') c = char(c - 'a' + 'A');
  for (const Glyph& g : kFont)
    if (g.c == c) return g.rows;
  return nullptr;
}

std::string formatTick(double v, double step) {
  char buf[32];
  if (step >= 1 && std::fabs(v - std::round(v)) < 1e-9)
    std::snprintf(buf, sizeof buf, "%.0f", v);
  else if (step >= 0.1)
    std::snprintf(buf, sizeof buf, "%.1f", v);
  else
    std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

}  // namespace

void Canvas::fillRect(int x, int y, int w, int h, uint32_t c) {
  for (int j = std::max(0, y); j < std::min(img.height, y + h); ++j)
    for (int i = std::max(0, x); i < std::min(img.width, x + w); ++i) img(i, j) = c;
}

void Canvas::line(double x0, double y0, double x1, double y1, uint32_t c, int thickness) {
  const double len = std::max(std::fabs(x1 - x0), std::fabs(y1 - y0));
  const int steps = std::max(1, int(std::ceil(len * 2)));
  const int h = thickness / 2;
  for (int s = 0; s <= steps; ++s) {
    const double f = double(s) / steps;
    const int x = int(std::lround(x0 + f * (x1 - x0))), y = int(std::lround(y0 + f * (y1 - y0)));
    fillRect(x - h, y - h, thickness, thickness, c);
  }
}

int Canvas::text(int x, int y, const std::string& s, uint32_t c, int scale) {
  int cx = x;
  for (char ch : s) {
    const uint8_t* g = glyph(ch);
    for (int row = 0; row < 7; ++row)
      for (int col = 0; col < 5; ++col) {
        const bool on = g ? (g[row] >> (4 - col)) & 1 : (row == 0 || row == 6 || col == 0 || col == 4);
        if (on) fillRect(cx + col * scale, y + row * scale, scale, scale, c);
      }
    cx += 6 * scale;
  }
  return cx - x;
}

void Canvas::blit(const RgbImage& src, int x, int y, int shrink) {
  shrink = std::max(1, shrink);
  for (int j = 0; j < src.height / shrink; ++j)
    for (int i = 0; i < src.width / shrink; ++i) {
      unsigned r = 0, g = 0, b = 0;
      for (int v = 0; v < shrink; ++v)
        for (int u = 0; u < shrink; ++u) {
          const uint32_t p = src(i * shrink + u, j * shrink + v);
          r += (p >> 16) & 0xff, g += (p >> 8) & 0xff, b += p & 0xff;
        }
      const unsigned n = unsigned(shrink * shrink);
      pixel(x + i, y + j, ((r / n) << 16) | ((g / n) << 8) | (b / n));
    }
}

void Canvas::marker(double x, double y, int kind, uint32_t c, int size) {
  const double s = size;
  switch (kind % 5) {
    case 0:
      for (int a = 0; a < 24; ++a) {
        const double t0 = a * 2 * M_PI / 24, t1 = (a + 1) * 2 * M_PI / 24;
        line(x + s * std::cos(t0), y + s * std::sin(t0), x + s * std::cos(t1), y + s * std::sin(t1), c, 2);
      }
      break;
    case 1:
      line(x - s, y - s, x + s, y + s, c, 2);
      line(x - s, y + s, x + s, y - s, c, 2);
      break;
    case 2:
      line(x - s, y + s, x + s, y + s, c, 2);
      line(x - s, y + s, x, y - s, c, 2);
      line(x + s, y + s, x, y - s, c, 2);
      break;
    case 3:
      line(x - s, y, x + s, y, c, 2);
      line(x, y - s, x, y + s, c, 2);
      break;
    default:
      fillRect(int(x - s + 1), int(y - s + 1), int(2 * s - 1), int(2 * s - 1), c);
  }
}

double niceStep(double range, int n) {
  if (!(range > 0)) return 1;
  const double raw = range / std::max(1, n);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

RgbImage linePlot(const PlotSpec& spec, const std::vector<Series>& series) {
  Canvas cv(spec.width, spec.height);
  bool right = false;
  for (const Series& s : series) right = right || s.rightAxis;
  const int left = 90, top = 80, bottom = spec.height - 70, rightEdge = spec.width - (right ? 90 : 30);
  const uint32_t axis = 0x202020, grid = 0xe4e4e4;
  auto X = [&](double v) { return left + (v - spec.xMin) / (spec.xMax - spec.xMin) * (rightEdge - left); };
  auto Y = [&](double v, bool r) {
    const double lo = r ? spec.yRightMin : spec.yMin, hi = r ? spec.yRightMax : spec.yMax;
    return bottom - (v - lo) / (hi - lo) * (bottom - top);
  };
  // Grid and ticks.
  const double xs = niceStep(spec.xMax - spec.xMin, 10), ys = niceStep(spec.yMax - spec.yMin, 7);
  for (double v = std::ceil(spec.xMin / xs - 1e-9) * xs; v <= spec.xMax + 1e-9; v += xs) {
    cv.line(X(v), top, X(v), bottom, grid);
    cv.line(X(v), bottom, X(v), bottom + 6, axis);
    const std::string t = formatTick(v, xs);
    cv.text(int(X(v)) - Canvas::textWidth(t, 2) / 2, bottom + 12, t, axis, 2);
  }
  for (double v = std::ceil(spec.yMin / ys - 1e-9) * ys; v <= spec.yMax + 1e-9; v += ys) {
    cv.line(left, Y(v, false), rightEdge, Y(v, false), grid);
    cv.line(left - 6, Y(v, false), left, Y(v, false), axis);
    const std::string t = formatTick(v, ys);
    cv.text(left - 10 - Canvas::textWidth(t, 2), int(Y(v, false)) - 7, t, axis, 2);
  }
  if (right) {
    const double rs = niceStep(spec.yRightMax - spec.yRightMin, 7);
    for (double v = std::ceil(spec.yRightMin / rs - 1e-9) * rs; v <= spec.yRightMax + 1e-9; v += rs) {
      cv.line(rightEdge, Y(v, true), rightEdge + 6, Y(v, true), axis);
      cv.text(rightEdge + 10, int(Y(v, true)) - 7, formatTick(v, rs), axis, 2);
    }
  }
  // Frame.
  cv.line(left, top, left, bottom, axis, 2);
  cv.line(left, bottom, rightEdge, bottom, axis, 2);
  cv.line(left, top, rightEdge, top, axis, 1);
  cv.line(rightEdge, top, rightEdge, bottom, axis, right ? 2 : 1);
  // Labels.
  cv.text(left, 12, spec.title, axis, 2);
  cv.text((left + rightEdge) / 2 - Canvas::textWidth(spec.xLabel, 2) / 2, spec.height - 28, spec.xLabel, axis, 2);
  cv.text(8, top - 30, spec.yLabel, axis, 2);
  if (right) cv.text(spec.width - 8 - Canvas::textWidth(spec.yLabelRight, 2), top - 30, spec.yLabelRight, axis, 2);
  // Series (clipped to the frame).
  for (const Series& s : series) {
    for (size_t i = 0; i + 1 < s.x.size(); ++i) {
      if (!std::isfinite(s.y[i]) || !std::isfinite(s.y[i + 1])) continue;
      cv.line(X(s.x[i]), std::max(double(top), std::min(double(bottom), Y(s.y[i], s.rightAxis))), X(s.x[i + 1]),
              std::max(double(top), std::min(double(bottom), Y(s.y[i + 1], s.rightAxis))), s.colour, 2);
    }
    for (size_t i = 0; i < s.x.size(); ++i)
      if (std::isfinite(s.y[i]) && Y(s.y[i], s.rightAxis) >= top && Y(s.y[i], s.rightAxis) <= bottom)
        cv.marker(X(s.x[i]), Y(s.y[i], s.rightAxis), s.marker, s.colour);
  }
  // Legend.
  int lw = 0;
  for (const Series& s : series) lw = std::max(lw, Canvas::textWidth(s.label, 2));
  const int lx = rightEdge - lw - 70, ly = top + 10, lh = int(series.size()) * 24 + 10;
  cv.fillRect(lx, ly, lw + 60, lh, 0xffffff);
  cv.line(lx, ly, lx + lw + 60, ly, axis);
  cv.line(lx, ly + lh, lx + lw + 60, ly + lh, axis);
  cv.line(lx, ly, lx, ly + lh, axis);
  cv.line(lx + lw + 60, ly, lx + lw + 60, ly + lh, axis);
  for (size_t i = 0; i < series.size(); ++i) {
    const int yy = ly + 17 + int(i) * 24;
    cv.line(lx + 8, yy, lx + 40, yy, series[i].colour, 2);
    cv.marker(lx + 24, yy, series[i].marker, series[i].colour);
    cv.text(lx + 50, yy - 7, series[i].label, axis, 2);
  }
  return cv.img;
}

}  // namespace cs::baselines

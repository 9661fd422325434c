// Small raster drawing for the evaluation's pictures: a canvas with lines, rectangles,
// a built-in 5x7 bitmap font, image tiles, and a line plot with axes and a legend.
// Colours are 0x00RRGGBB as writePngRgb expects.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "curvestereo/image.hpp"

namespace cs::baselines {

using RgbImage = Image<uint32_t>;

class Canvas {
 public:
  Canvas(int w, int h, uint32_t background = 0xffffff) : img(w, h, background) {}
  RgbImage img;

  void pixel(int x, int y, uint32_t c) {
    if (img.inside(x, y)) img(x, y) = c;
  }
  void fillRect(int x, int y, int w, int h, uint32_t c);
  void line(double x0, double y0, double x1, double y1, uint32_t c, int thickness = 1);
  // Text in the 5x7 font (lower case is drawn as upper case), `scale` px per font pixel;
  // returns the width drawn. Unknown characters are drawn as a hollow box.
  int text(int x, int y, const std::string& s, uint32_t c, int scale = 1);
  static int textWidth(const std::string& s, int scale = 1) { return int(s.size()) * 6 * scale; }
  // Copies src at (x, y), shrunk by an integer factor (box average per channel).
  void blit(const RgbImage& src, int x, int y, int shrink = 1);
  void marker(double x, double y, int kind, uint32_t c, int size = 4);  // 0 o, 1 x, 2 triangle, 3 +, 4 square
};

struct Series {
  std::string label;
  std::vector<double> x, y;
  uint32_t colour = 0;
  int marker = 0;
  bool rightAxis = false;
};

struct PlotSpec {
  std::string title, xLabel, yLabel, yLabelRight;
  double xMin = 0, xMax = 1, yMin = 0, yMax = 1, yRightMin = 0, yRightMax = 1;
  int width = 900, height = 560;
};

// A line plot: frame, ticks with numbers on both axes (right axis only when a series
// uses it), every series as a polyline with markers, and a legend in the top-right.
RgbImage linePlot(const PlotSpec& spec, const std::vector<Series>& series);

// "Nice" tick step for a range (1, 2 or 5 times a power of ten, ~n ticks).
double niceStep(double range, int n);

}  // namespace cs::baselines

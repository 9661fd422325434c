// eval --sparsification FILE: how well ours's confidence ranks its pixels, per pair (metrics.hpp
// sparsification): a CSV of the curves, a line per pair on the terminal, and a plot of the mean
// curve beside the oracle's.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "baselines/draw.hpp"
#include "curvestereo/image_io.hpp"
#include "eval.hpp"

namespace cs::cli::eval {

namespace {

// tau>1 of the most confident 80 % over all pixels' (the figure issue 28's target is stated in).
double ratioAt80(const Sparsification& s) {
  for (size_t i = 0; i < s.keptPercent.size(); ++i)
    if (s.keptPercent[i] == 80) return s.tau[i] / s.tau[0];
  return NAN;
}

baselines::Series meanSeries(const std::vector<std::pair<std::string, Sparsification>>& curves, bool oracle,
                             const char* label, uint32_t colour, int marker) {
  baselines::Series s{label, {}, {}, colour, marker, false};
  const Sparsification& first = curves.front().second;
  for (size_t i = 0; i < first.keptPercent.size(); ++i) {
    double sum = 0;
    for (const auto& c : curves) sum += oracle ? c.second.oracleTau[i] : c.second.tau[i];
    s.x.push_back(first.keptPercent[i]);
    s.y.push_back(sum / double(curves.size()));
  }
  return s;
}

void plotCurves(const std::string& path, const std::vector<std::pair<std::string, Sparsification>>& curves) {
  const baselines::Series ours = meanSeries(curves, false, "ranked by confidence", 0xd0208f, 1);
  const baselines::Series oracle = meanSeries(curves, true, "ranked by true error (oracle)", 0x1f5fd0, 0);
  baselines::PlotSpec spec;
  spec.title = "sparsification: tau>1 of the most confident pixels (" + std::to_string(curves.size()) + " pairs)";
  spec.xLabel = "pixels kept (%)";
  spec.yLabel = "% erroneous pixels (tau>1)";
  spec.xMin = 100;
  spec.xMax = 50;
  double yMax = 0;
  for (double y : ours.y) yMax = std::max(yMax, y);
  const double step = baselines::niceStep(std::max(yMax, 1.0) * 1.1, 7);
  spec.yMax = std::ceil(std::max(yMax, 1.0) * 1.1 / step) * step;
  writePngRgb(path, baselines::linePlot(spec, {ours, oracle}));
}

}  // namespace

void printSparsification(const std::string& pair, const Sparsification& s) {
  std::printf("%-22s sparsification: area %.2f %% (oracle %.2f %%); tau>1 of the most confident 80 %% = %.2fx all\n",
              pair.c_str(), s.area, s.oracleArea, ratioAt80(s));
}

void writeSparsification(const std::string& path, const std::vector<std::pair<std::string, Sparsification>>& curves) {
  std::ofstream csv(path);
  if (!csv) throw Error("cannot write '" + path + "'");
  csv << "pair,kept_percent,tau1,oracle_tau1,area,oracle_area\n";
  for (const auto& [pair, s] : curves)
    for (size_t i = 0; i < s.keptPercent.size(); ++i)
      csv << pair << ',' << s.keptPercent[i] << ',' << s.tau[i] << ',' << s.oracleTau[i] << ',' << s.area << ','
          << s.oracleArea << '\n';
  if (!curves.empty()) plotCurves(std::filesystem::path(path).replace_extension(".png").string(), curves);
}

}  // namespace cs::cli::eval

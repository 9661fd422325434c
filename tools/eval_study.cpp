// `eval --sweep warps=A..B | dumax=A..B`: the paper's two parameter studies (error and
// time against the warps N; error against du_max for several N), as CSV and a line plot.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>

#include "baselines/draw.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/stereo.hpp"
#include "eval.hpp"

namespace cs::cli::eval {

namespace {

namespace fs = std::filesystem;

struct SweepPoint {
  int warps;
  double duMax;
  std::string pair;
  Metrics m;
  double tau5, ms;
};

}  // namespace

int runStudy(const Args& args, const Params& base, const std::string& backend) {
  const std::string spec = args.get("sweep", "");
  const size_t eq = spec.find('='), dots = spec.find("..");
  if (eq == std::string::npos || dots == std::string::npos || dots < eq)
    throw Error("option --sweep expects warps=A..B or dumax=A..B, got '" + spec + "'");
  const std::string what = spec.substr(0, eq);
  const double a = numberList(spec.substr(eq + 1, dots - eq - 1), "sweep")[0];
  const double b = numberList(spec.substr(dots + 2), "sweep")[0];
  if (what != "warps" && what != "dumax")
    throw Error("option --sweep: unknown parameter '" + what + "' (warps, dumax)");
  if (!(b >= a)) throw Error("option --sweep: empty range");
  std::vector<int> warpsList;
  std::vector<double> duList;
  if (what == "warps") {
    for (int n = int(std::lround(a)); n <= int(std::lround(b)); ++n) warpsList.push_back(n);
    duList.push_back(base.duMax);
  } else {
    const double step = args.getDouble("step", 0.1);
    for (double d = a; d <= b + 1e-9; d += step) duList.push_back(std::round(d * 1000) / 1000);
    for (double n : numberList(args.get("warps-list", "5,10,20"), "warps-list")) warpsList.push_back(int(n));
  }
  std::vector<Pair> pairs;
  const bool replot = args.has("replot");  // --replot on: redraw the plot from an existing --csv
  if (!replot)
    for (const std::string& dir : args.positional()) pairs.push_back(loadPair(dir));
  const std::string csv = args.require("csv");
  const std::string plot = args.get("plot", fs::path(csv).replace_extension(".png").string());

  std::vector<SweepPoint> points;
  auto flush = [&]() {
    std::ofstream f(csv);
    if (!f) throw Error("cannot write '" + csv + "'");
    f << "sweep,warps,du_max,pair,tau1,tau3,tau5,epe,density,ms\n";
    char buf[256];
    for (const SweepPoint& p : points) {
      std::snprintf(buf, sizeof buf, "%s,%d,%.3f,%s,%.3f,%.3f,%.3f,%.4f,%.3f,%.1f\n", what.c_str(), p.warps, p.duMax,
                    p.pair.c_str(), p.m.tau1, p.m.tau3, p.tau5, p.m.epe, p.m.density, p.ms);
      f << buf;
    }
  };
  if (replot) {
    std::ifstream f(csv);
    if (!f) throw Error("cannot read '" + csv + "'");
    std::string line;
    std::getline(f, line);
    std::set<std::string> names;
    while (std::getline(f, line)) {
      std::vector<std::string> c = splitList(line);
      if (c.size() < 10) continue;
      SweepPoint sp{std::stoi(c[1]), std::stod(c[2]), c[3], Metrics{}, std::stod(c[6]), std::stod(c[9])};
      sp.m.tau1 = std::stod(c[4]), sp.m.tau3 = std::stod(c[5]), sp.m.epe = std::stod(c[7]),
      sp.m.density = std::stod(c[8]);
      points.push_back(sp);
      names.insert(c[3]);
    }
    pairs.resize(names.size());
  }
  for (int n : warpsList)
    for (double du : duList)
      for (const Pair& pr : pairs) {
        if (replot) break;
        Params p = base;
        p.warps = n;
        p.duMax = float(du);
        p.validate();
        Stereo stereo(pr.rig, p, backend);
        DepthResult r = stereo.compute(pr.left, pr.right);
        ImageF error;
        Metrics m = evaluate(pr.rig, r.warp, r.depth.radial, pr.depthLeft,
                             pr.depthRight.empty() ? nullptr : &pr.depthRight, &error);
        points.push_back({n, du, pr.name, m, tauPercent(error, 5.0, Missing::Bad), r.totalMs});
        std::printf("%s N=%d du_max=%.2f  tau>1 %.2f %%  tau>3 %.2f %%  tau>5 %.2f %%  %.0f ms\n", pr.name.c_str(), n,
                    du, m.tau1, m.tau3, points.back().tau5, r.totalMs);
        std::fflush(stdout);
        flush();
      }

  // Means over the pairs, then the plot.
  auto mean = [&](int n, double du, auto get) {
    double s = 0;
    int c = 0;
    for (const SweepPoint& p : points)
      if (p.warps == n && std::fabs(p.duMax - du) < 1e-6) s += get(p), ++c;
    return c ? s / c : NAN;
  };
  baselines::PlotSpec plotSpec;
  std::vector<baselines::Series> series;
  const uint32_t palette[] = {0xd0208f, 0x1f5fd0, 0xe04020, 0x20a040, 0x8040c0, 0x00a0b0};
  double yMax = 0;
  if (what == "warps") {
    baselines::Series t1{"tau>1 px", {}, {}, 0xd0208f, 1, false}, t5{"tau>5 px", {}, {}, 0xd0208f, 0, false},
        tm{"time (ms)", {}, {}, 0x1f5fd0, 2, true};
    double tMax = 0;
    for (int n : warpsList) {
      t1.x.push_back(n), t5.x.push_back(n), tm.x.push_back(n);
      t1.y.push_back(mean(n, duList[0], [](const SweepPoint& p) { return p.m.tau1; }));
      t5.y.push_back(mean(n, duList[0], [](const SweepPoint& p) { return p.tau5; }));
      tm.y.push_back(mean(n, duList[0], [](const SweepPoint& p) { return p.ms; }));
      yMax = std::max(yMax, t1.y.back());
      tMax = std::max(tMax, tm.y.back());
    }
    series = {t5, t1, tm};
    plotSpec.title = "error and time vs warping iterations (du_max " + fovName(duList[0]) + " px, " +
                     std::to_string(pairs.size()) + " pairs)";
    plotSpec.xLabel = "warping iterations N";
    plotSpec.yLabel = "% erroneous pixels";
    plotSpec.yLabelRight = "time (ms)";
    plotSpec.xMin = warpsList.front();
    plotSpec.xMax = std::max(warpsList.back(), warpsList.front() + 1);
    const double rs = baselines::niceStep(tMax * 1.1, 7);
    plotSpec.yRightMax = std::ceil(tMax * 1.1 / rs) * rs;
  } else {
    for (size_t i = 0; i < warpsList.size(); ++i) {
      baselines::Series s{"N=" + std::to_string(warpsList[i]), {}, {}, palette[i % 6], int(i), false};
      for (double du : duList) {
        s.x.push_back(du);
        s.y.push_back(mean(warpsList[i], du, [](const SweepPoint& p) { return p.m.tau1; }));
        yMax = std::max(yMax, s.y.back());
      }
      series.push_back(s);
    }
    plotSpec.title = "tau>1 vs du_max (" + std::to_string(pairs.size()) + " pairs)";
    plotSpec.xLabel = "du_max (px)";
    plotSpec.yLabel = "% erroneous pixels (tau>1)";
    plotSpec.xMin = duList.front();
    plotSpec.xMax = std::max(duList.back(), duList.front() + 0.1);
  }
  const double ys = baselines::niceStep(yMax * 1.1, 7);
  plotSpec.yMax = std::max(ys, std::ceil(yMax * 1.1 / ys) * ys);
  writePngRgb(plot, baselines::linePlot(plotSpec, series));
  std::printf("wrote %s and %s\n", csv.c_str(), plot.c_str());
  return 0;
}

}  // namespace cs::cli::eval

// curvestereo eval PAIRDIR... --csv FILE [--md FILE] [--maps DIR] [--methods LIST]
//   accuracy of our method and of the paper's baselines on pairs with ground truth
//   (DESIGN.md "Evaluation definitions"), or, with --sweep, the paper's two parameter
//   studies (error and time vs warps N; error vs du_max for several N) as CSV + PNG plot.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "baselines/draw.hpp"
#include "baselines/methods.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/metrics.hpp"

namespace cs::cli {

namespace {

namespace fs = std::filesystem;
using baselines::MethodResult;
using baselines::RgbImage;

struct Row {
  std::string pair, method;
  Metrics m;
  double ms;
  double tau1Est = 0, tau3Est = 0;  // over pixels with an estimate only (the paper's planesweep-valid convention)
};

// tau>k over the evaluated pixels that have an estimate (error map finite).
double tauEstimated(const ImageF& error, double k) {
  long long n = 0, bad = 0;
  for (float e : error.data) {
    if (!std::isfinite(e)) continue;
    ++n;
    bad += e > k;
  }
  return n ? 100.0 * double(bad) / double(n) : 0.0;
}

const char* kCsvHeader = "pair,method,tau1,tau3,epe,tau1_noc,tau3_noc,epe_noc,absrel,density,ms";

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

struct Pair {
  std::string dir, name;
  Rig rig;
  ImageF left, right, depthLeft, depthRight;
};

Pair loadPair(const std::string& dir) {
  auto in = [&](const char* name) { return (fs::path(dir) / name).string(); };
  Pair p;
  p.dir = dir;
  const fs::path norm = fs::path(dir).lexically_normal();
  p.name = norm.filename().string().empty() ? norm.parent_path().filename().string() : norm.filename().string();
  p.rig = loadKalibr(in("camchain.yaml"));
  p.left = loadImageFor(in("left.png"), p.rig.cam0, "left");
  p.right = loadImageFor(in("right.png"), p.rig.cam1, "right");
  p.depthLeft = readExr(in("depth_left.exr"));
  if (p.depthLeft.width != p.left.width || p.depthLeft.height != p.left.height)
    throw Error("'" + in("depth_left.exr") + "' does not match the image size");
  if (fs::exists(in("depth_right.exr"))) p.depthRight = readExr(in("depth_right.exr"));
  return p;
}

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}
std::vector<double> numberList(const std::string& s, const char* option) {
  std::vector<double> out;
  for (const std::string& item : splitList(s)) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (!end || *end || !std::isfinite(v))
      throw Error(std::string("option --") + option + " expects numbers, got '" + item + "'");
    out.push_back(v);
  }
  if (out.empty()) throw Error(std::string("option --") + option + " is empty");
  return out;
}
std::string fovName(double fov) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", fov);
  return buf;
}

// The methods of one run, in table order.
struct Plan {
  std::vector<std::string> methods;  // ours, rectified-tgv-F, planesweep, planesweep-valid, opencv-sgbm-F
};

Plan makePlan(const Args& args) {
  const std::vector<double> fovs = numberList(args.get("fov", "90,165"), "fov");
  const std::vector<double> sgbmFovs = numberList(args.get("sgbm-fov", "120"), "sgbm-fov");
  std::vector<std::string> want = splitList(args.get("methods", "ours"));
  Plan plan;
  auto add = [&](const std::string& m) {
    if (std::find(plan.methods.begin(), plan.methods.end(), m) == plan.methods.end()) plan.methods.push_back(m);
  };
  for (const std::string& m : want) {
    if (m == "all" || m == "ours") add("ours");
    if (m == "all" || m == "rectified-tgv")
      for (double f : fovs) add("rectified-tgv-" + fovName(f));
    if (m == "all" || m == "planesweep") add("planesweep");
    if (m == "all" || m == "planesweep-valid") add("planesweep-valid");
    if (m == "all" || m == "opencv-sgbm") {
      if (baselines::sgbmAvailable()) {
        for (double f : sgbmFovs) add("opencv-sgbm-" + fovName(f));
      } else {
        std::fprintf(stderr,
                     "eval: opencv-sgbm is unavailable (built without OpenCV: install libopencv-dev and re-run cmake); "
                     "skipped\n");
      }
    }
    const bool known = m == "all" || m == "ours" || m == "rectified-tgv" || m == "planesweep" ||
                       m == "planesweep-valid" || m == "opencv-sgbm";
    if (!known) {
      if (m.rfind("rectified-tgv-", 0) == 0) {
        numberList(m.substr(14), "methods");
        add(m);
      } else if (m.rfind("opencv-sgbm-", 0) == 0) {
        numberList(m.substr(12), "methods");
        if (!baselines::sgbmAvailable())
          throw Error("method " + m +
                      " is unavailable: curvestereo was built without OpenCV (install libopencv-dev and re-run cmake)");
        add(m);
      } else {
        throw Error("unknown method '" + m +
                    "' (known: ours, rectified-tgv[-FOV], planesweep, planesweep-valid, opencv-sgbm[-FOV], all)");
      }
    }
  }
  if (plan.methods.empty()) throw Error("no method to evaluate");
  return plan;
}

baselines::PlaneSweepOptions sweepOptions(const Args& args) {
  baselines::PlaneSweepOptions o;
  o.sweep.scale = args.getDouble("ps-scale", o.sweep.scale);
  o.sweep.window = args.getInt("ps-window", o.sweep.window);
  o.sweep.pxPerPlane = args.getDouble("ps-step", o.sweep.pxPerPlane);
  o.sweep.minDepth = args.getDouble("min-depth", o.sweep.minDepth);
  return o;
}

// Runs every planned method on one pair; returns the rows and (for the sheet) results.
std::vector<Row> evaluatePair(const Pair& p, const Plan& plan, const Args& args, const Params& params,
                              const std::string& backend, const std::string& maps) {
  std::map<std::string, MethodResult> results;
  MethodResult psAll, psValid;
  bool psDone = false;
  for (const std::string& m : plan.methods) {
    std::fprintf(stderr, "%s: %s ...\n", p.name.c_str(), m.c_str());
    if (m == "ours") {
      Stereo stereo(p.rig, params, backend);
      Progress progress(p.name);
      stereo.setProgress([&](double f) { progress(f); });
      DepthResult r = stereo.compute(p.left, p.right);
      progress.done();
      results[m] = MethodResult{r.warp, r.depth.radial, r.totalMs};
    } else if (m.rfind("rectified-tgv-", 0) == 0) {
      const double fov = std::stod(m.substr(14));
      results[m] = baselines::runRectifiedTgv(p.rig, p.left, p.right, params, backend, fov, p.left.width);
    } else if (m == "planesweep" || m == "planesweep-valid") {
      if (!psDone) baselines::runPlaneSweep(p.rig, p.left, p.right, sweepOptions(args), psAll, psValid);
      psDone = true;
      results[m] = m == "planesweep" ? psAll : psValid;
    } else if (m.rfind("opencv-sgbm-", 0) == 0) {
      const double fov = std::stod(m.substr(12));
      results[m] = baselines::runSgbm(p.rig, p.left, p.right, baselines::SgbmOptions{}, fov, p.left.width);
    }
  }

  std::vector<Row> rows;
  std::map<std::string, ImageF> errors;
  const ImageF* dr = p.depthRight.empty() ? nullptr : &p.depthRight;
  for (const std::string& m : plan.methods) {
    const MethodResult& r = results[m];
    ImageF error;
    rows.push_back({p.name, m, evaluate(p.rig, r.warp, r.depth, p.depthLeft, dr, &error), r.ms});
    rows.back().tau1Est = tauEstimated(error, 1.0);
    rows.back().tau3Est = tauEstimated(error, 3.0);
    errors[m] = std::move(error);
  }

  if (!maps.empty()) {
    fs::create_directories(maps);
    const DepthScale scale = depthScale(p.depthLeft);
    // Sheet: column 0 = input over ground truth; then per method its depth over its error.
    const int shrink = p.left.width > 500 ? 2 : 1;
    const int tw = p.left.width / shrink, th = p.left.height / shrink, label = 24, gap = 6;
    const int cols = 1 + int(plan.methods.size());
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
    for (size_t i = 0; i < plan.methods.size(); ++i) {
      const std::string& m = plan.methods[i];
      const Row& row = rows[rows.size() - plan.methods.size() + i];
      tile(int(i) + 1, 0, depthPicture(results[m].depth, scale), m);
      std::snprintf(buf, sizeof buf, "t>1 %.1f%% t>3 %.1f%%", row.m.tau1, row.m.tau3);
      tile(int(i) + 1, 1, errorPicture(errors[m]), buf);
      writePngRgb((fs::path(maps) / (p.name + "_" + m + "_error.png")).string(), errorPicture(errors[m]));
      writeDepthPng((fs::path(maps) / (p.name + "_" + m + "_depth.png")).string(), results[m].depth);
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
  return rows;
}

void writeCsv(const std::string& path, const std::vector<Row>& rows) {
  std::ofstream f(path);
  if (!f) throw Error("cannot write '" + path + "'");
  f << kCsvHeader << "\n";
  char buf[512];
  for (const Row& r : rows) {
    std::snprintf(buf, sizeof buf, "%s,%s,%.3f,%.3f,%.4f,%.3f,%.3f,%.4f,%.5f,%.3f,%.1f\n", r.pair.c_str(),
                  r.method.c_str(), r.m.tau1, r.m.tau3, r.m.epe, r.m.tau1Noc, r.m.tau3Noc, r.m.epeNoc, r.m.absRel,
                  r.m.density, r.ms);
    f << buf;
  }
}

std::string markdown(const std::vector<Row>& rows, const Params& params, const Args& args) {
  std::vector<std::string> pairs, methods;
  std::map<std::pair<std::string, std::string>, const Row*> at;
  for (const Row& r : rows) {
    if (std::find(pairs.begin(), pairs.end(), r.pair) == pairs.end()) pairs.push_back(r.pair);
    if (std::find(methods.begin(), methods.end(), r.method) == methods.end()) methods.push_back(r.method);
    at[{r.pair, r.method}] = &r;
  }
  std::string s =
      "Settings (ours and rectified-tgv): " + describe(params) + "; backend " + args.get("backend", "auto") + "\n\n";
  struct Col {
    const char* title;
    double (*get)(const Row&);
    const char* fmt;
    bool lowerBetter;
  };
  const Col cols[] = {
      {"tau>1 % (all pixels)", [](const Row& r) { return r.m.tau1; }, "%.2f", true},
      {"tau>3 %", [](const Row& r) { return r.m.tau3; }, "%.2f", true},
      {"end-point error px", [](const Row& r) { return r.m.epe; }, "%.3f", true},
      {"tau>1 % non-occluded", [](const Row& r) { return r.m.tau1Noc; }, "%.2f", true},
      {"tau>1 % over estimated pixels only (missing pixels not counted; the paper's convention for planesweep-valid)",
       [](const Row& r) { return r.tau1Est; }, "%.2f", true},
      {"tau>3 % over estimated pixels only", [](const Row& r) { return r.tau3Est; }, "%.2f", true},
      {"depth abs-rel % (where estimated)", [](const Row& r) { return 100 * r.m.absRel; }, "%.2f", true},
      {"density %", [](const Row& r) { return r.m.density; }, "%.1f", false},
      {"time ms", [](const Row& r) { return r.ms; }, "%.0f", true},
  };
  char buf[64];
  for (const Col& c : cols) {
    s += std::string("### ") + c.title + "\n\n| pair |";
    for (auto& m : methods) s += " " + m + " |";
    s += "\n|---|";
    for (size_t i = 0; i < methods.size(); ++i) s += "---|";
    s += "\n";
    for (auto& p : pairs) {
      s += "| " + p + " |";
      double best = c.lowerBetter ? 1e300 : -1e300;
      for (auto& m : methods)
        if (at.count({p, m}))
          best = c.lowerBetter ? std::min(best, c.get(*at[{p, m}])) : std::max(best, c.get(*at[{p, m}]));
      for (auto& m : methods) {
        if (!at.count({p, m})) {
          s += " - |";
          continue;
        }
        const double v = c.get(*at[{p, m}]);
        std::snprintf(buf, sizeof buf, c.fmt, v);
        s += (v == best && methods.size() > 1) ? std::string(" **") + buf + "** |" : std::string(" ") + buf + " |";
      }
      s += "\n";
    }
    s += "\n";
  }
  return s;
}

// ---- --sweep warps=A..B | dumax=A..B ----

struct SweepPoint {
  int warps;
  double duMax;
  std::string pair;
  Metrics m;
  double tau5, ms;
};

double tauFromError(const ImageF& error, double k) {
  long long n = 0, bad = 0;
  for (float e : error.data) {
    if (std::isnan(e)) continue;
    ++n;
    if (e > k) ++bad;
  }
  return n ? 100.0 * double(bad) / double(n) : 0.0;
}

int runSweep(const Args& args, const Params& base, const std::string& backend) {
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
        points.push_back({n, du, pr.name, m, tauFromError(error, 5.0), r.totalMs});
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

}  // namespace

int cmdEval(const Args& args) {
  std::set<std::string> known = kSolverOptions;
  known.insert({"csv", "md", "maps", "methods", "fov", "sgbm-fov", "ps-scale", "ps-window", "ps-step", "min-depth",
                "sweep", "warps-list", "step", "plot", "replot"});
  args.allowOnly(known);
  if (args.positional().empty()) throw Error("eval needs at least one pair folder");
  const Params params = paramsFromArgs(args);
  const std::string backend = backendFromArgs(args);
  if (args.has("sweep")) return runSweep(args, params, backend);
  const std::string csv = args.require("csv");
  const Plan plan = makePlan(args);
  std::vector<Row> rows;
  for (const std::string& dir : args.positional()) {
    const Pair pair = loadPair(dir);
    for (const Row& r : evaluatePair(pair, plan, args, params, backend, args.get("maps", ""))) {
      rows.push_back(r);
      std::printf(
          "%-22s %-18s tau>1 %6.2f %%  tau>3 %6.2f %%  EPE %7.3f px  abs-rel %5.2f %%  density %5.1f %%  %6.0f ms\n",
          r.pair.c_str(), r.method.c_str(), r.m.tau1, r.m.tau3, r.m.epe, 100 * r.m.absRel, r.m.density, r.ms);
    }
    std::fflush(stdout);
    writeCsv(csv, rows);  // rewritten after each pair so a long run leaves partial results
    if (args.has("md")) {
      std::ofstream md(args.get("md", ""));
      if (!md) throw Error("cannot write '" + args.get("md", "") + "'");
      md << markdown(rows, params, args);
    }
  }
  std::printf("wrote %s\n", csv.c_str());
  return 0;
}

}  // namespace cs::cli

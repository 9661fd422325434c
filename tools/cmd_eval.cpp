// curvestereo eval PAIRDIR... --csv FILE [--md FILE] [--maps DIR]: accuracy on pairs
// with ground truth (DESIGN.md "Evaluation definitions").
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/metrics.hpp"

namespace cs::cli {

namespace {

struct Row {
  std::string pair, method;
  Metrics m;
  double ms;
};

const char* kCsvHeader = "pair,method,tau1,tau3,epe,tau1_noc,tau3_noc,epe_noc,absrel,density,ms";

// The paper's error bins (px): 0, 0.19, 0.75, 3, 24, 48, inf; blue (good) to red (bad).
Image<uint32_t> errorPicture(const ImageF& error) {
  static const float edges[] = {0.19f, 0.75f, 3.f, 24.f, 48.f};
  static const uint32_t colours[] = {0x313695, 0x74add1, 0xfee090, 0xf46d43, 0xd73027, 0xa50026};
  Image<uint32_t> out(error.width, error.height, 0);
  for (size_t i = 0; i < error.size(); ++i) {
    float e = error.data[i];
    if (std::isnan(e)) continue;
    int bin = 0;
    while (bin < 5 && e > edges[bin]) ++bin;
    out.data[i] = colours[bin];
  }
  return out;
}

Row evaluatePair(const std::string& dir, const Params& params, const std::string& backend, const std::string& maps) {
  namespace fs = std::filesystem;
  auto in = [&](const char* name) { return (fs::path(dir) / name).string(); };
  const Rig rig = loadKalibr(in("camchain.yaml"));
  const ImageF left = loadImageFor(in("left.png"), rig.cam0, "left");
  const ImageF right = loadImageFor(in("right.png"), rig.cam1, "right");
  const ImageF depthLeft = readExr(in("depth_left.exr"));
  if (depthLeft.width != left.width || depthLeft.height != left.height)
    throw Error("'" + in("depth_left.exr") + "' does not match the image size");
  ImageF depthRight;
  if (fs::exists(in("depth_right.exr"))) depthRight = readExr(in("depth_right.exr"));

  Stereo stereo(rig, params, backend);
  const std::string name = fs::path(dir).lexically_normal().filename().string().empty()
                               ? fs::path(dir).lexically_normal().parent_path().filename().string()
                               : fs::path(dir).lexically_normal().filename().string();
  Progress progress(name);
  stereo.setProgress([&](double f) { progress(f); });
  DepthResult r = stereo.compute(left, right);
  progress.done();

  ImageF error;
  Row row{name, "ours", evaluate(rig, r.warp, r.depth.radial, depthLeft, depthRight.empty() ? nullptr : &depthRight, &error),
          r.totalMs};
  if (!maps.empty()) {
    fs::create_directories(maps);
    writePngRgb((fs::path(maps) / (name + "_error.png")).string(), errorPicture(error));
    writeDepthPng((fs::path(maps) / (name + "_depth.png")).string(), r.depth.radial);
  }
  return row;
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

std::string markdown(const std::vector<Row>& rows, const Params& params) {
  std::string s = "Settings: " + describe(params) + "\n\n";
  s += "| pair | method | tau>1 % | tau>3 % | EPE px | tau>1 noc % | tau>3 noc % | EPE noc px | abs-rel % | density % | ms |\n";
  s += "|---|---|---|---|---|---|---|---|---|---|---|\n";
  char buf[512];
  for (const Row& r : rows) {
    std::snprintf(buf, sizeof buf, "| %s | %s | %.2f | %.2f | %.3f | %.2f | %.2f | %.3f | %.2f | %.1f | %.0f |\n",
                  r.pair.c_str(), r.method.c_str(), r.m.tau1, r.m.tau3, r.m.epe, r.m.tau1Noc, r.m.tau3Noc, r.m.epeNoc,
                  100 * r.m.absRel, r.m.density, r.ms);
    s += buf;
  }
  return s;
}

}  // namespace

int cmdEval(const Args& args) {
  std::set<std::string> known = kSolverOptions;
  known.insert({"csv", "md", "maps"});
  args.allowOnly(known);
  if (args.positional().empty()) throw Error("eval needs at least one pair folder");
  const std::string csv = args.require("csv");
  const Params params = paramsFromArgs(args);
  std::vector<Row> rows;
  for (const std::string& dir : args.positional()) {
    rows.push_back(evaluatePair(dir, params, backendFromArgs(args), args.get("maps", "")));
    const Row& r = rows.back();
    std::printf("%-24s tau>1 %6.2f %%  tau>3 %6.2f %%  EPE %.3f px  (noc: %.2f / %.2f %%)  %.0f ms\n", r.pair.c_str(),
                r.m.tau1, r.m.tau3, r.m.epe, r.m.tau1Noc, r.m.tau3Noc, r.ms);
    std::fflush(stdout);
    writeCsv(csv, rows);  // rewritten after each pair so a long run leaves partial results
  }
  if (args.has("md")) {
    std::ofstream md(args.get("md", ""));
    if (!md) throw Error("cannot write '" + args.get("md", "") + "'");
    md << markdown(rows, params);
  }
  std::printf("wrote %s\n", csv.c_str());
  return 0;
}

}  // namespace cs::cli

// `eval`'s tables: one CSV row per pair and method, and Markdown tables per metric with
// the best method of each pair in bold.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>

#include "curvestereo/image.hpp"
#include "eval.hpp"

namespace cs::cli::eval {

namespace {

const char* kCsvHeader = "pair,method,tau1,tau3,epe,tau1_noc,tau3_noc,epe_noc,absrel,density,ms,sky";

}  // namespace

void writeCsv(const std::string& path, const std::vector<Row>& rows) {
  std::ofstream f(path);
  if (!f) throw Error("cannot write '" + path + "'");
  f << kCsvHeader << "\n";
  char buf[512];
  for (const Row& r : rows) {
    std::snprintf(buf, sizeof buf, "%s,%s,%.3f,%.3f,%.4f,%.3f,%.3f,%.4f,%.5f,%.3f,%.1f,%.2f\n", r.pair.c_str(),
                  r.method.c_str(), r.m.tau1, r.m.tau3, r.m.epe, r.m.tau1Noc, r.m.tau3Noc, r.m.epeNoc, r.m.absRel,
                  r.m.density, r.ms, r.m.sky);
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

}  // namespace cs::cli::eval

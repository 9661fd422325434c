#include "curvestereo/param_table.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "curvestereo/backend.hpp"
#include "curvestereo/image.hpp"

namespace cs {

namespace {

using Type = ParamInfo::Type;
using Shown = ParamInfo::Shown;

constexpr double kInf = std::numeric_limits<double>::infinity();

// A range [lo, hi], with either end open.
struct Range {
  double lo = -kInf, hi = kInf;
  bool loOpen = false, hiOpen = false;
};
Range closed(double lo, double hi) { return {lo, hi, false, false}; }
Range above(double lo) { return {lo, kInf, true, false}; }
Range atLeast(double lo) { return {lo, kInf, false, false}; }

ParamInfo base(const char* name, Type type, Range r, const char* help, Shown shown) {
  ParamInfo i;
  i.name = name;
  i.type = type;
  i.lo = r.lo, i.hi = r.hi, i.loOpen = r.loOpen, i.hiOpen = r.hiOpen;
  i.help = help;
  i.shown = shown;
  return i;
}

ParamInfo intParam(const char* name, int Params::*f, Range r, const char* help, Shown shown = Shown::Always) {
  ParamInfo i = base(name, Type::Int, r, help, shown);
  i.intField = f;
  return i;
}

ParamInfo floatParam(const char* name, float Params::*f, Range r, const char* help, Shown shown = Shown::Always) {
  ParamInfo i = base(name, Type::Float, r, help, shown);
  i.floatField = f;
  return i;
}

ParamInfo doubleParam(const char* name, double Params::*f, Range r, const char* help, Shown shown = Shown::Always) {
  ParamInfo i = base(name, Type::Double, r, help, shown);
  i.doubleField = f;
  return i;
}

ParamInfo withAlias(ParamInfo i, const char* alias) {
  i.alias = alias;
  return i;
}

std::vector<ParamInfo> grouped(const char* group, std::vector<ParamInfo> list) {
  for (ParamInfo& i : list) i.group = group;
  return list;
}

std::vector<ParamInfo> buildTable() {
  ParamInfo median =
      base("median_filter", Type::Bool, {}, "3x3 median of the disparity after each warp", Shown::Always);
  median.alias = "median";
  median.boolField = &Params::medianFilter;

  ParamInfo edgeUpsample = base("edge_upsample", Type::Bool, {},
                                "at the coarse estimate's depth edges, each pixel takes the coarse neighbour its "
                                "images match best instead of a bilinear blend",
                                Shown::Always);
  edgeUpsample.boolField = &Params::edgeUpsample;

  ParamInfo dataTerm =
      base("data_term", Type::Enum, {}, "what the data term compares; also sets lambda's default", Shown::Always);
  dataTerm.describeKey = "data";
  dataTerm.choices = {"normalised", "brightness"};
  dataTerm.noun = "data term";
  dataTerm.getChoice = [](const Params& p) { return p.dataTerm == Params::DataTerm::Normalised ? 0 : 1; };
  dataTerm.setChoice = [](Params& p, int c) {
    p = p.withDataTerm(c == 0 ? Params::DataTerm::Normalised : Params::DataTerm::Brightness);
  };

  ParamInfo init = base("init", Type::Enum, {}, "initialiser of the disparity", Shown::Always);
  init.choices = {"none", "planesweep"};
  init.noun = "initialisation";
  init.getChoice = [](const Params& p) { return p.init == Params::Init::PlaneSweep ? 1 : 0; };
  init.setChoice = [](Params& p, int c) { p.init = c == 1 ? Params::Init::PlaneSweep : Params::Init::None; };

  const Range any;  // finite
  std::vector<ParamInfo> table = grouped(
      "solver",
      {
          intParam("levels", &Params::levels, closed(1, 12), "pyramid levels (fewer if narrower than min-width)"),
          doubleParam("scale", &Params::scale, {1, 4, true, false}, "size ratio of neighbouring pyramid levels"),
          intParam("min_width", &Params::minWidth, atLeast(8), "smallest level width and height, px", Shown::Never),
          intParam("warps", &Params::warps, closed(1, 1000),
                   "warps (outer iterations) per level (at the coarsest, with warps_taper)"),
          intParam("warps_taper", &Params::warpsTaper, closed(0, 1000),
                   "each finer level warps this many times fewer (at least once)", Shown::Always),
          intParam("iterations", &Params::iterations, closed(1, 1000), "primal-dual iterations per warp"),
          floatParam("du_max", &Params::duMax, above(0), "largest disparity step per warp, px of the level"),
          dataTerm,
          floatParam("norm_sigma", &Params::normSigma, closed(0.5, kMaxNormaliseRadius / 3),
                     "contrast normalisation window (Gaussian sigma, level px)", Shown::Normalised),
          floatParam("noise_level", &Params::noiseLevel, {0, 1, true, false},
                     "camera noise, grey levels of [0, 1]: contrast below it is not trusted", Shown::Normalised),
          floatParam("lambda", &Params::lambda, above(0), "data term weight (default 3 normalised, 20 brightness)"),
          floatParam("alpha0", &Params::alpha0, above(0), "TGV weight of |grad v|"),
          floatParam("alpha1", &Params::alpha1, above(0), "TGV weight of |D grad u - v|"),
          floatParam("beta", &Params::beta, atLeast(0), "structure tensor: edge weight exp(-beta |grad I|^eta)"),
          floatParam("eta", &Params::eta, above(0), "structure tensor: exponent eta"),
          floatParam("w_min", &Params::wMin, {0, 1, true, false}, "structure tensor: smallest edge weight",
                     Shown::Never),
          floatParam("tensor_sigma", &Params::tensorSigma, closed(0, 10),
                     "Gaussian smoothing (px) of the image before its gradient", Shown::Never),
          median,
          edgeUpsample,
          floatParam("gamma", &Params::gamma, atLeast(0), "accelerated primal-dual (0: constant steps)"),
      });
  std::vector<ParamInfo> sweep =
      grouped("plane-sweep initialiser (on in --preset realtime, fast and quality)",
              {
                  init,
                  intParam("init_level", &Params::initLevel, {0, 12, false, true},
                           "pyramid level of the sweep (0: full)", Shown::PlaneSweep),
                  withAlias(doubleParam("init_max_parallax_deg", &Params::initMaxParallaxDeg, {0, 90, true, true},
                                        "nearest hypothesis: this much parallax, degrees", Shown::PlaneSweep),
                            "init_parallax"),
                  doubleParam("init_px_per_plane", &Params::initPxPerPlane, closed(0.25, 16),
                              "largest image motion between neighbouring hypotheses, level px", Shown::Never),
                  intParam("init_radius", &Params::initRadius, closed(1, 7), "ZNCC window radius", Shown::PlaneSweep),
                  floatParam("init_p1", &Params::initP1, any, "aggregation: penalty of a step (0 <= p1 <= p2)",
                             Shown::PlaneSweep),
                  floatParam("init_p2", &Params::initP2, any, "aggregation: penalty of a jump", Shown::PlaneSweep),
                  floatParam("lr_tolerance_px", &Params::lrTolerancePx, above(0),
                             "left-right error (level px) where confidence is 1/e", Shown::Never),
                  floatParam("init_accept", &Params::initAccept, closed(0, 1),
                             "confidence from which the sweep replaces the coarse estimate", Shown::Never),
                  floatParam("init_max_cost", &Params::initMaxCost, closed(0, 2),
                             "a sweep winner of a higher cost (1 - ZNCC) is not accepted (2: all)", Shown::Never),
                  floatParam("occlusion_weight", &Params::occlusionWeight, closed(0, 1),
                             "data-term weight floor of low-confidence pixels", Shown::PlaneSweep),
                  intParam("init_warps", &Params::initWarps, closed(0, 1000),
                           "warps per level from the sweep's down (0: as the levels above)", Shown::PlaneSweep),
                  intParam("init_band", &Params::initBand, closed(0, 32),
                           "hypotheses a pixel at the sweep's level around a sweep one level coarser (0: full sweep)",
                           Shown::PlaneSweep),
              });
  std::vector<ParamInfo> view =
      grouped("field of view",
              {
                  withAlias(doubleParam("max_fov_deg", &Params::maxFovDeg, closed(0, 360),
                                        "field of view used, degrees (0: all the model represents)", Shown::Never),
                            "max_fov"),
                  withAlias(doubleParam("epipole_deg", &Params::epipoleDeg, {0, 90, false, true},
                                        "mask rays this close to the baseline, degrees", Shown::Never),
                            "epipole"),
              });
  ParamInfo warm = base("warm_start", Type::Bool, {},
                        "sequences: start each frame from the previous one's estimate (needs init_band)", Shown::Never);
  warm.boolField = &Params::warmStart;
  std::vector<ParamInfo> sequence = grouped(
      "sequences (run --sequence, Stereo::next)",
      {
          warm,
          intParam("warm_band", &Params::warmBand, closed(0, 32),
                   "hypotheses a pixel of a warm frame's band sweep (0: init_band's)", Shown::Never),
          intParam("warm_coarse_warps", &Params::warmCoarseWarps, closed(0, 1000),
                   "warps at each level above the carried one in a warm frame (0: skipped)", Shown::Never),
          intParam("warm_full_res_warps", &Params::warmFullResWarps, closed(0, 1000),
                   "warps at full resolution in a warm frame (0: init_warps')", Shown::Never),
          intParam("cold_every", &Params::coldEvery, closed(0, 1000000),
                   "solve every N-th frame cold (0: only the first and failed ones)", Shown::Never),
          floatParam("warm_fail_ratio", &Params::warmFailRatio, closed(0, 1),
                     "a warm frame with fewer consistent pixels or less mean confidence than this x the last cold "
                     "one's is redone cold (0: no check)",
                     Shown::Never),
          floatParam("temporal_strength", &Params::temporalStrength, {0, 1, false, true},
                     "temporal filter: the carried depth's largest weight (0: off)", Shown::Never),
          floatParam("temporal_gate", &Params::temporalGate, above(0),
                     "temporal filter: reset a pixel beyond this many standard deviations", Shown::Never),
      });
  ParamInfo lrCheck = base(
      "lr_check", Type::Bool, {},
      "solve the other direction too; pixels whose round trip fails become invalid (run prints the share that passes)",
      Shown::Always);
  lrCheck.boolField = &Params::lrCheck;
  ParamInfo plainFill =
      base("plain_fill", Type::Bool, {}, "fill each large plain region with the plane its textured border agrees on",
           Shown::Always);
  plainFill.boolField = &Params::plainFill;
  std::vector<ParamInfo> trust = grouped(
      "confidence and validity (every preset)",
      {
          plainFill,
          intParam("plain_fill_level", &Params::plainFillLevel, closed(0, 12),
                   "pyramid level whose estimate plain_fill corrects (clamped to the coarsest)", Shown::Never),
          lrCheck,
          floatParam("lr_check_px", &Params::lrCheckPx, above(0),
                     "lr_check: a round trip beyond this (px) leaves the pixel invalid", Shown::Always),
          floatParam("infinity_px", &Params::infinityPx, closed(0, 10),
                     "a disparity below this (px) is a point at infinity", Shown::Never),
          floatParam(
              "infinity_bound_px", &Params::infinityBoundPx, closed(0, 10),
              "a disparity within two deviations of 0 and bounded by them below this (px) is at infinity (0: off)",
              Shown::Never),
          floatParam("max_deviation_px", &Params::maxDeviationPx, closed(0, 1000),
                     "leave invalid the pixels whose image fixes the disparity no better than this (px; 0: keep)",
                     Shown::Always),
          floatParam("reject_below", &Params::rejectBelow, closed(0, 1),
                     "leave invalid the pixels whose confidence is below this", Shown::Always),
      });
  table.insert(table.end(), trust.begin(), trust.end());
  table.insert(table.end(), sweep.begin(), sweep.end());
  table.insert(table.end(), sequence.begin(), sequence.end());
  table.insert(table.end(), view.begin(), view.end());
  return table;
}

std::string kebab(const char* s) {
  std::string r = s;
  for (char& c : r)
    if (c == '_') c = '-';
  return r;
}

std::string numText(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace

const std::vector<ParamInfo>& paramTable() {
  static const std::vector<ParamInfo> table = buildTable();
  return table;
}

const ParamInfo& paramInfo(const std::string& name) {
  for (const ParamInfo& info : paramTable())
    if (name == info.name || (info.alias && name == info.alias)) return info;
  throw Error("unknown parameter '" + name + "'");
}

std::string ParamInfo::cliName() const { return kebab(alias ? alias : name); }
std::string ParamInfo::cliLongName() const { return kebab(name); }

std::string ParamInfo::cppName() const {
  std::string r;
  bool up = false;
  for (const char* c = name; *c; ++c) {
    if (*c == '_') {
      up = true;
      continue;
    }
    r += up ? char(std::toupper((unsigned char)*c)) : *c;
    up = false;
  }
  return r;
}

std::string ParamInfo::key() const { return describeKey ? describeKey : alias ? alias : name; }

double ParamInfo::number(const Params& p) const {
  switch (type) {
    case Type::Int:
      return p.*intField;
    case Type::Float:
      return p.*floatField;
    case Type::Double:
      return p.*doubleField;
    default:
      throw Error(std::string("parameter ") + name + " is not a number");
  }
}

void ParamInfo::setNumber(Params& p, double v) const {
  switch (type) {
    case Type::Int:
      p.*intField = int(v);
      break;
    case Type::Float:
      p.*floatField = float(v);
      break;
    case Type::Double:
      p.*doubleField = v;
      break;
    default:
      throw Error(std::string("parameter ") + name + " is not a number");
  }
}

std::string ParamInfo::text(const Params& p) const {
  std::ostringstream s;
  switch (type) {
    case Type::Int:
      s << p.*intField;
      break;
    case Type::Float:
      s << p.*floatField;
      break;
    case Type::Double:
      s << p.*doubleField;
      break;
    case Type::Bool:
      s << (p.*boolField ? "on" : "off");
      break;
    case Type::Enum:
      s << choices[size_t(getChoice(p))];
      break;
  }
  return s.str();
}

void ParamInfo::setChoiceNamed(Params& p, const std::string& choice) const {
  for (size_t c = 0; c < choices.size(); ++c)
    if (choices[c] == choice) return setChoice(p, int(c));
  std::string known;
  for (const auto& c : choices) known += (known.empty() ? "" : ", ") + c;
  throw Error("unknown " + std::string(noun) + " '" + choice + "' (known: " + known + ")");
}

std::string ParamInfo::rangeText() const {
  const bool hasLo = std::isfinite(lo), hasHi = std::isfinite(hi);
  if (hasLo && hasHi) return (loOpen ? "(" : "[") + numText(lo) + ", " + numText(hi) + (hiOpen ? ")" : "]");
  if (hasLo) return (loOpen ? "> " : ">= ") + numText(lo);
  if (hasHi) return (hiOpen ? "< " : "<= ") + numText(hi);
  return "";
}

std::string ParamInfo::rangeError(const Params& p) const {
  if (type != Type::Int && type != Type::Float && type != Type::Double) return "";
  // Compared in double: every field converts to it exactly.
  const double v = number(p);
  const bool ok = std::isfinite(v) && (loOpen ? v > lo : v >= lo) && (hiOpen ? v < hi : v <= hi);
  if (ok) return "";
  const std::string range = rangeText();
  if (range.empty()) return "must be finite";
  return std::isfinite(lo) && std::isfinite(hi) ? "must be in " + range : "must be " + range;
}

}  // namespace cs

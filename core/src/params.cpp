#include "curvestereo/params.hpp"

#include <cmath>
#include <sstream>

#include "curvestereo/backend.hpp"
#include "curvestereo/image.hpp"

namespace cs {

namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw Error("invalid parameter: " + what);
}

}  // namespace

void Params::validate() const {
  require(levels >= 1 && levels <= 12, "levels must be in [1, 12]");
  require(std::isfinite(scale) && scale > 1.0 && scale <= 4.0, "scale must be in (1, 4]");
  require(minWidth >= 8, "minWidth must be >= 8");
  require(warps >= 1 && warps <= 1000, "warps must be in [1, 1000]");
  require(iterations >= 1 && iterations <= 1000, "iterations must be in [1, 1000]");
  require(std::isfinite(duMax) && duMax > 0, "duMax must be > 0");
  require(std::isfinite(normSigma) && normSigma >= 0.5f && 3.f * normSigma <= float(kMaxNormaliseRadius),
          "normSigma must be in [0.5, " + std::to_string(kMaxNormaliseRadius / 3) + "]");
  require(std::isfinite(noiseLevel) && noiseLevel > 0 && noiseLevel <= 1, "noiseLevel must be in (0, 1]");
  require(std::isfinite(lambda) && lambda > 0, "lambda must be > 0");
  require(std::isfinite(alpha0) && alpha0 > 0, "alpha0 must be > 0");
  require(std::isfinite(alpha1) && alpha1 > 0, "alpha1 must be > 0");
  require(std::isfinite(beta) && beta >= 0, "beta must be >= 0");
  require(std::isfinite(eta) && eta > 0, "eta must be > 0");
  require(std::isfinite(wMin) && wMin > 0 && wMin <= 1, "wMin must be in (0, 1]");
  require(std::isfinite(tensorSigma) && tensorSigma >= 0 && tensorSigma <= 10, "tensorSigma must be in [0, 10]");
  require(std::isfinite(gamma) && gamma >= 0, "gamma must be >= 0");
  require(initLevel >= 0 && initLevel < 12, "initLevel must be in [0, 12)");
  require(std::isfinite(initMaxParallaxDeg) && initMaxParallaxDeg > 0 && initMaxParallaxDeg < 90,
          "initMaxParallaxDeg must be in (0, 90)");
  require(std::isfinite(initPxPerPlane) && initPxPerPlane >= 0.25 && initPxPerPlane <= 16,
          "initPxPerPlane must be in [0.25, 16]");
  require(initRadius >= 1 && initRadius <= 7, "initRadius must be in [1, 7]");
  require(std::isfinite(initP1) && std::isfinite(initP2) && initP1 >= 0 && initP2 >= initP1,
          "initP1, initP2 must satisfy 0 <= initP1 <= initP2");
  require(std::isfinite(lrTolerancePx) && lrTolerancePx > 0, "lrTolerancePx must be > 0");
  require(std::isfinite(initAccept) && initAccept >= 0 && initAccept <= 1, "initAccept must be in [0, 1]");
  require(initWarps >= 0 && initWarps <= 1000, "initWarps must be in [0, 1000]");
  require(std::isfinite(occlusionWeight) && occlusionWeight >= 0 && occlusionWeight <= 1,
          "occlusionWeight must be in [0, 1]");
  require(std::isfinite(maxFovDeg) && maxFovDeg >= 0 && maxFovDeg <= 360, "maxFovDeg must be in [0, 360]");
  require(std::isfinite(epipoleDeg) && epipoleDeg >= 0 && epipoleDeg < 90, "epipoleDeg must be in [0, 90)");
}

Params preset(const std::string& name) {
  // The struct's defaults are the "default" preset: N = 30 warps reach the ~100 px
  // displacements of near objects on 12-30 cm baselines; more warps (50) and a stronger or
  // weaker data term (lambda 12..30) changed tau>1 by under 0.5 points on the development
  // pairs, and the accelerated schedule (gamma > 0) lost accuracy with warm-started warps.
  Params p;
  if (name == "default") return p;
  if (name == "realtime") {
    // N = 5 with a plane sweep at level 2 (a quarter of the resolution): measured on the 12
    // development pairs (CUDA, H100), mean tau>1 of clean binocular / T265-like binocular /
    // clean and T265-like forward non-occluded pairs 7.7 / 11.4 / 14.0 / 22.8 % against
    // 24.6 / 26.1 / 49.7 / 51.8 % without the sweep, for ~1.6 ms more per 848x800 frame
    // (3.1 -> 4.7 ms): coarse-to-fine warping alone reaches only N x 0.2 px per level.
    p.warps = 5;
    p.init = Params::Init::PlaneSweep;
    p.initLevel = 2;
    return p;
  }
  if (name == "paper") {
    // Roxas & Oishi, Sec. IV: brightness constancy, 5 levels x2, N=5, K=10, du_max 0.2.
    p = p.withDataTerm(Params::DataTerm::Brightness);
    p.warps = 5;
    return p;
  }
  if (name == "quality") {
    p.init = Params::Init::PlaneSweep;
    return p;
  }
  std::string known;
  for (auto& n : presetNames()) known += (known.empty() ? "" : ", ") + n;
  throw Error("unknown preset '" + name + "' (known: " + known + ")");
}

std::vector<std::string> presetNames() { return {"realtime", "default", "quality", "paper"}; }

Params Params::withDataTerm(DataTerm term) const {
  Params p = *this;
  p.dataTerm = term;
  p.lambda = term == DataTerm::Normalised ? kNormalisedLambda : kBrightnessLambda;
  return p;
}

std::string dataTermName(Params::DataTerm term) {
  return term == Params::DataTerm::Normalised ? "normalised" : "brightness";
}

Params::DataTerm parseDataTerm(const std::string& name) {
  if (name == "normalised") return Params::DataTerm::Normalised;
  if (name == "brightness") return Params::DataTerm::Brightness;
  throw Error("unknown data term '" + name + "' (known: normalised, brightness)");
}

NormaliseParams normaliseParams(const Params& p) {
  NormaliseParams n{};
  n.radius = std::min(kMaxNormaliseRadius, int(std::ceil(3.f * p.normSigma)));
  float sum = 0.f;
  for (int i = -n.radius; i <= n.radius; ++i)
    sum += n.taps[i + n.radius] = std::exp(-float(i * i) / (2.f * p.normSigma * p.normSigma));
  for (int i = 0; i <= 2 * n.radius; ++i) n.taps[i] /= sum;
  n.epsilon = p.noiseLevel;
  return n;
}

std::string initName(Params::Init init) { return init == Params::Init::PlaneSweep ? "planesweep" : "none"; }

Params::Init parseInit(const std::string& name) {
  if (name == "none") return Params::Init::None;
  if (name == "planesweep") return Params::Init::PlaneSweep;
  throw Error("unknown initialisation '" + name + "' (known: none, planesweep)");
}

std::vector<LevelSize> pyramidPlan(int width, int height, const Params& p) {
  std::vector<LevelSize> plan{{width, height, 1.0}};
  for (int l = 1; l < p.levels; ++l) {
    double s = std::pow(p.scale, -l);
    int w = int(std::ceil(width * s)), h = int(std::ceil(height * s));
    if (w < p.minWidth || h < p.minWidth) break;
    plan.push_back({w, h, s});
  }
  return plan;
}

std::string describe(const Params& p) {
  std::ostringstream s;
  s << "levels=" << p.levels << " scale=" << p.scale << " warps=" << p.warps << " iterations=" << p.iterations
    << " du_max=" << p.duMax << " lambda=" << p.lambda << " alpha0=" << p.alpha0 << " alpha1=" << p.alpha1
    << " data=" << dataTermName(p.dataTerm);
  if (p.dataTerm == Params::DataTerm::Normalised) s << " norm_sigma=" << p.normSigma << " noise_level=" << p.noiseLevel;
  s << " beta=" << p.beta << " eta=" << p.eta << " median=" << (p.medianFilter ? "on" : "off") << " gamma=" << p.gamma
    << " init=" << initName(p.init);
  if (p.init == Params::Init::PlaneSweep)
    s << " init_level=" << p.initLevel << " init_parallax=" << p.initMaxParallaxDeg << " init_radius=" << p.initRadius
      << " init_p1=" << p.initP1 << " init_p2=" << p.initP2 << " occlusion_weight=" << p.occlusionWeight
      << " init_warps=" << p.initWarps;
  return s.str();
}

}  // namespace cs

#include "curvestereo/params.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "curvestereo/backend.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/param_table.hpp"
#include "curvestereo/pipeline_params.hpp"

namespace cs {

namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw Error("invalid parameter: " + what);
}

}  // namespace

void Params::validate() const {
  for (const ParamInfo& info : paramTable()) {
    const std::string bad = info.rangeError(*this);
    require(bad.empty(), info.cppName() + " " + bad);
  }
  require(initP1 >= 0 && initP2 >= initP1, "initP1, initP2 must satisfy 0 <= initP1 <= initP2");
  require(initBand != 1, "initBand must be 0 (a full sweep) or 2 to 32 hypotheses, got 1");
  require(warmBand != 1, "warmBand must be 0 (initBand's) or 2 to 32 hypotheses, got 1");
}

Params preset(const std::string& name) {
  // The struct's defaults are the "variational" preset, the solver alone: N = 30 warps
  // reach the ~100 px displacements of near objects on 12-30 cm baselines; more warps (50)
  // and a stronger or weaker data term (lambda 12..30) changed tau>1 by under 0.5 points on
  // the development pairs, and the accelerated schedule (gamma > 0) lost accuracy with
  // warm-started warps.
  Params p;
  if (name == "variational") return p;
  if (name == "realtime") {
    // A full sweep at level 2, checked and initialising level 2, then a band of 32
    // hypotheses a pixel around its winners at level 1 (initBand); warps where they are
    // needed: the coarse levels travel from zero for the pixels the checks reject (30, 20
    // at levels 4, 3: the coarsest does the travelling), the levels the sweeps initialise
    // and the full resolution only refine (2 each), each from the coarser estimate
    // resampled without blending surfaces across depth edges (edgeUpsample). Measured on
    // the 12 development pairs (CUDA, H200; the CPU oracle agrees), mean tau>1 / tau>3 %
    // of clean binocular, T265-like binocular pairs and tau>1 of clean / T265-like forward
    // non-occluded pairs: 4.8 / 2.8, 6.4 / 3.3, 8.2 / 15.3 in 4.3 ms a 848x800 frame
    // (bilinear upsampling: 5.8 / 3.5, 7.3 / 4.0, 10.0 / 17.2; quality: 4.7 / 3.4,
    // 6.5 / 3.8, 6.6 / 16.3 in 12.6 ms). Bands of 16 and 24 lost 0.1 to 0.2 points for
    // 0.1 ms; 30 warps at all coarse levels cost 0.9 ms more, 20 / 12 / 4 lost 0.1 to 0.2
    // points, dropping levels 3 and 4 lost 4 to 6 (docs/accuracy.md "How realtime was chosen").
    p.init = Params::Init::PlaneSweep;
    p.edgeUpsample = true;
    p.initLevel = 1;
    p.warps = 30;
    p.warpsTaper = 10;
    p.initWarps = 2;
    p.initBand = 32;
    return p;
  }
  if (name == "fast") {
    // realtime's predecessor, for slower GPUs: a plane sweep at level 2 (a quarter of the
    // resolution, a sixth of level 1's sweep time), then N = 5 warps a level. With 5 warps
    // the step per warp is chosen so that a level can still travel about as far as the N =
    // 30 presets (5 x 1.0 px against 30 x 0.2): the sweep's upsampled estimate is several
    // level px off at edges. Measured as realtime's above: 5.4 / 4.0, 8.2 / 5.3, 9.6 %,
    // about 0.9 ms less per 848x800 frame on an H200. (The tapered schedule after a
    // level-2 sweep measured worse, 8.4 / 9.9 % tau>1: a coarse sweep leaves the fine
    // levels more to travel.)
    p.warps = 5;
    p.duMax = 1.f;
    p.init = Params::Init::PlaneSweep;
    p.edgeUpsample = true;
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
    p.edgeUpsample = true;
    return p;
  }
  std::string known;
  for (auto& n : presetNames()) known += (known.empty() ? "" : ", ") + n;
  if (name == "default")  // the name until realtime became the default (issue 15)
    throw Error("preset 'default' is now called 'variational'; without a preset, realtime is used (known: " + known +
                ")");
  throw Error("unknown preset '" + name + "' (known: " + known + ")");
}

std::vector<std::string> presetNames() { return {"realtime", "fast", "quality", "variational", "paper"}; }

Params Params::withDataTerm(DataTerm term) const {
  Params p = *this;
  p.dataTerm = term;
  p.lambda = term == DataTerm::Normalised ? kNormalisedLambda : kBrightnessLambda;
  return p;
}

std::string dataTermName(Params::DataTerm term) {
  Params p;
  p.dataTerm = term;
  return paramInfo("data_term").text(p);
}

Params::DataTerm parseDataTerm(const std::string& name) {
  Params p;
  paramInfo("data_term").setChoiceNamed(p, name);
  return p.dataTerm;
}

NormaliseParams normaliseParams(const Params& p) {
  const std::vector<float> taps = gaussianTaps(p.normSigma);
  NormaliseParams n{};
  if (taps.size() > std::size(n.taps)) throw Error("invalid parameter: normSigma " + std::to_string(p.normSigma));
  std::copy(taps.begin(), taps.end(), n.taps);
  n.radius = int(taps.size() / 2);
  n.epsilon = p.noiseLevel;
  return n;
}

std::string initName(Params::Init init) {
  Params p;
  p.init = init;
  return paramInfo("init").text(p);
}

Params::Init parseInit(const std::string& name) {
  Params p;
  paramInfo("init").setChoiceNamed(p, name);
  return p.init;
}

LevelSize levelSize(int width, int height, double scale) {
  return {int(std::ceil(width * scale)), int(std::ceil(height * scale)), scale};
}

std::vector<LevelSize> pyramidPlan(int width, int height, const Params& p) {
  std::vector<LevelSize> plan{{width, height, 1.0}};
  for (int l = 1; l < p.levels; ++l) {
    const LevelSize level = levelSize(width, height, std::pow(p.scale, -l));
    if (level.width < p.minWidth || level.height < p.minWidth) break;
    plan.push_back(level);
  }
  return plan;
}

int sweepLevel(const Params& p, int levels) { return std::min(levels - 1, p.initLevel); }

bool sweepBanded(const Params& p, int levels) {
  return p.init == Params::Init::PlaneSweep && p.initBand > 0 && sweepLevel(p, levels) + 1 < levels;
}

std::vector<int> warpSchedule(const Params& p, int levels, bool warm) {
  std::vector<int> warps(size_t(std::max(0, levels)));
  const int sweep = sweepLevel(p, levels) + (sweepBanded(p, levels) ? 1 : 0);
  for (int l = 0; l < levels; ++l) {
    if (p.init == Params::Init::PlaneSweep && l <= sweep && p.initWarps > 0)
      warps[size_t(l)] = p.initWarps;
    else
      warps[size_t(l)] = std::max(1, p.warps - p.warpsTaper * (levels - 1 - l));
  }
  if (warm) {
    for (int l = sweep + 1; l < levels; ++l) warps[size_t(l)] = p.warmCoarseWarps;
    if (p.warmFullResWarps > 0 && levels > 0) warps[0] = p.warmFullResWarps;
  }
  return warps;
}

std::string describe(const Params& p) {
  std::string s;
  for (const ParamInfo& info : paramTable()) {
    using Shown = ParamInfo::Shown;
    const bool shown = info.shown == Shown::Always ||
                       (info.shown == Shown::Normalised && p.dataTerm == Params::DataTerm::Normalised) ||
                       (info.shown == Shown::PlaneSweep && p.init == Params::Init::PlaneSweep);
    if (shown) s += (s.empty() ? "" : " ") + info.key() + "=" + info.text(p);
  }
  return s;
}

}  // namespace cs

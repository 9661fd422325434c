#include "pipeline.hpp"

#include <chrono>
#include <cmath>

namespace cs {

namespace {

double nowMs() {
  using namespace std::chrono;
  return duration<double, std::milli>(steady_clock::now().time_since_epoch()).count();
}

std::vector<float> toFloats(const ImageU8& mask) { return std::vector<float>(mask.data.begin(), mask.data.end()); }

std::vector<float> toFloats(const FlowImage& flow) {
  std::vector<float> out(flow.size() * 2);
  for (size_t i = 0; i < flow.size(); ++i) {
    out[2 * i] = flow.data[i].x;
    out[2 * i + 1] = flow.data[i].y;
  }
  return out;
}

// The level's camera: the same lens imaged at the level's resolution.
Camera levelCamera(const Camera& cam, const LevelSize& size) {
  Camera c = cam.scaled(size.scale);
  c.width = size.width;
  c.height = size.height;
  return c;
}

// The user's mask (full resolution) seen from a level: nearest pixel.
ImageU8 combineMasks(const ImageU8& levelMask, const ImageU8& userMask, double scale) {
  if (userMask.empty()) return levelMask;
  ImageU8 out = levelMask;
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      int ux = std::min(userMask.width - 1, int(std::lround((x + 0.5) / scale - 0.5)));
      int uy = std::min(userMask.height - 1, int(std::lround((y + 0.5) / scale - 0.5)));
      if (!userMask(ux, uy)) out(x, y) = 0;
    }
  return out;
}

}  // namespace

void StageClock::start(const std::string& name) {
  backend_.synchronize();
  double t = nowMs();
  if (!current_.empty()) {
    bool found = false;
    for (auto& s : stages_)
      if (s.name == current_) s.ms += t - startedMs_, found = true;
    if (!found) stages_.push_back({current_, t - startedMs_});
  }
  current_ = name;
  startedMs_ = t;
}

std::vector<StageTime> StageClock::finish() {
  start("");
  current_.clear();
  return std::move(stages_);
}

Pipeline::Pipeline(Backend& backend, const Rig& rig, const Params& params, const RigFields& fields,
                   const ImageU8& userMask)
    : backend_(backend), params_(params), clock_(backend) {
  const Camera& cam0 = rig.cam0;
  const FieldOptions fieldOptions{params.maxFovDeg, params.epipoleDeg};
  for (const LevelSize& size : pyramidPlan(cam0.width, cam0.height, params)) {
    // Fields are computed exactly at each level from the scaled cameras rather than
    // resampled from level 0: the same cost (once per rig) and no averaging of tangents.
    RigFields f = size.scale == 1.0 ? fields
                                    : computeFields(levelCamera(cam0, size), levelCamera(rig.cam1, size), rig.R,
                                                    rig.t, fieldOptions);
    f.mask = combineMasks(f.mask, userMask, size.scale);

    Level L;
    L.size = size;
    auto make = [&](int channels) { return backend_.create(size.width, size.height, channels); };
    L.i0 = make(1), L.i1 = make(1), L.mask = make(1), L.trajectory = make(2);
    L.tensor = make(4), L.steps = make(4), L.w = make(2), L.tangent = make(2), L.scratch = make(1);
    L.pd = {make(1), make(1), make(2), make(2), make(2), make(4)};
    L.data = {make(1), make(1), make(1)};
    backend_.upload(L.mask, toFloats(f.mask).data());
    backend_.upload(L.trajectory, toFloats(f.trajectory).data());
    levels_.push_back(L);
  }
  rawRight_ = backend_.create(cam0.width, cam0.height, 1);
  calibration_ = backend_.create(cam0.width, cam0.height, 2);
  backend_.upload(calibration_, toFloats(fields.calibration).data());
}

void Pipeline::buildPyramid(const ImageF& left, const ImageF& right) {
  clock_.start("upload");
  backend_.upload(levels_[0].i0, left.data.data());
  backend_.upload(rawRight_, right.data.data());
  clock_.start("calibration warp");
  backend_.warp(levels_[0].i1, rawRight_, calibration_);
  clock_.start("pyramid");
  for (size_t l = 1; l < levels_.size(); ++l) {
    backend_.downsample(levels_[l].i0, levels_[l - 1].i0, float(params_.scale));
    backend_.downsample(levels_[l].i1, levels_[l - 1].i1, float(params_.scale));
  }
}

void Pipeline::initialiseLevel(size_t l) {
  Level& L = levels_[l];
  clock_.start("structure tensor");
  const TensorParams tp{params_.beta, params_.eta, params_.wMin, params_.tensorSigma, params_.alpha0, params_.alpha1};
  backend_.structureTensor(L.tensor, L.steps, L.i0, L.mask, tp);
  clock_.start("upsample");
  if (l + 1 == levels_.size()) {
    backend_.fill(L.pd.u, 0.f);
    backend_.fill(L.w, 0.f);
  } else {
    const Level& coarse = levels_[l + 1];
    const float s = float(params_.scale);
    backend_.upsample(L.pd.u, coarse.pd.u, s, s);
    backend_.upsample(L.w, coarse.w, s, s);
  }
  for (const Buffer* b : {&L.pd.v, &L.pd.p, &L.pd.q}) backend_.fill(*b, 0.f);
}

PrimalDualParams Pipeline::primalDualParams() const {
  PrimalDualParams p{params_.lambda, params_.alpha0, params_.alpha1, {}};
  // Chambolle & Pock (2011) Alg. 2: tau_{k+1} = theta_k tau_k, sigma_{k+1} = sigma_k / theta_k,
  // theta_k = 1 / sqrt(1 + 2 gamma tau_k), with tau measured relative to the preconditioner.
  float scale = 1.f;
  for (int k = 0; k < params_.iterations; ++k) {
    float theta = 1.f / std::sqrt(1.f + 2.f * params_.gamma * scale);
    p.schedule.push_back({scale, 1.f / scale, theta});
    scale *= theta;
  }
  return p;
}

void Pipeline::solveLevel(Level& L, const std::function<void(int)>& warpDone) {
  const PrimalDualParams pdParams = primalDualParams();
  for (int n = 0; n < params_.warps; ++n) {
    clock_.start("warp derivatives");
    backend_.warpDerivatives(L.data, L.tangent, L.i0, L.i1, L.trajectory, L.w, L.pd.u, L.mask);
    clock_.start("primal-dual");
    backend_.copy(L.pd.uBar, L.pd.u);
    backend_.copy(L.pd.vBar, L.pd.v);
    backend_.primalDual(L.pd, L.data, L.tensor, L.steps, L.mask, pdParams);
    if (params_.medianFilter) {
      clock_.start("median");
      backend_.median(L.scratch, L.pd.u, L.mask);
      backend_.copy(L.pd.u, L.scratch);
    }
    clock_.start("accumulate");
    backend_.accumulate(L.pd.u, L.w, L.data.u0, L.tangent, L.mask, params_.duMax);
    warpDone(n);
  }
}

Pipeline::Output Pipeline::run(const ImageF& left, const ImageF& right,
                               const std::function<void(double)>& progress) {
  // Work per level is proportional to its pixel count: report progress in those units.
  double total = 0, done = 0;
  for (const Level& L : levels_) total += double(L.size.width) * L.size.height;
  buildPyramid(left, right);
  for (size_t l = levels_.size(); l-- > 0;) {
    initialiseLevel(l);
    const double share = double(levels_[l].size.width) * levels_[l].size.height / params_.warps;
    solveLevel(levels_[l], [&](int) {
      done += share;
      if (progress) progress(done / total);
    });
  }
  clock_.start("download");
  const Level& L0 = levels_[0];
  Output out;
  out.disparity = ImageF(L0.size.width, L0.size.height);
  std::vector<float> w(L0.w.count());
  backend_.download(L0.pd.u, out.disparity.data.data());
  backend_.download(L0.w, w.data());
  out.warp = FlowImage(L0.size.width, L0.size.height);
  for (size_t i = 0; i < out.warp.size(); ++i) out.warp.data[i] = {w[2 * i], w[2 * i + 1]};
  out.stages = clock_.finish();
  return out;
}

}  // namespace cs

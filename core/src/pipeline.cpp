#include "pipeline.hpp"

#include "curvestereo/parallel.hpp"
#include "stereo_core.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <type_traits>

namespace cs {

namespace {

// The level's camera: the same lens imaged at the level's resolution.
Camera levelCamera(const Camera& cam, const LevelSize& size) {
  Camera c = cam.scaled(size.scale);
  c.width = size.width;
  c.height = size.height;
  return c;
}

// The user's mask (full resolution) seen from a level: nearest pixel; all ones if none.
std::vector<float> levelMask(const ImageU8& userMask, const LevelSize& size) {
  std::vector<float> out(size_t(size.width) * size.height, 1.f);
  if (userMask.empty()) return out;
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) {
      int ux = std::min(userMask.width - 1, int(std::lround((x + 0.5) / size.scale - 0.5)));
      int uy = std::min(userMask.height - 1, int(std::lround((y + 0.5) / size.scale - 0.5)));
      out[size_t(y) * size.width + x] = userMask(ux, uy) ? 1.f : 0.f;
    }
  return out;
}

}  // namespace

// The other direction's solve (Params::lrCheck): camera 1 as the reference.
static Rig reversedRig(const Rig& rig) {
  Rig r;
  r.cam0 = rig.cam1;
  r.cam1 = rig.cam0;
  r.R = rig.R.transpose();
  r.t = -(rig.R.transpose() * rig.t);
  return r;
}

static Params reverseParams(Params p) {
  p.lrCheck = false;
  p.rejectBelow = 0.f;
  p.maxDeviationPx = 0.f;
  return p;
}

// Keep in step with the constructor below: 34 floats per pixel per level (userMask, i0, i1,
// mask, scratch 1; trajectory, w, tangent 2; tensor, steps 4; pd 12; data 3), 5 more with
// the normalised data term (n0, n1 1; moments 3), plus 10 at
// level 0 (rawRight 1, calibration 2, radial 1, points 3, confidence 1, valid 1, z 1; with lrCheck the
// round trip's error 1 and the other direction's pipeline, which has no valid or z); with the initialiser, a
// confidence (1) at the sweep level and every finer one (and the coarser one with a band), and the volume and the costs
// (planes each) and two sweep results (2 + 2) at the sweep level; with a band, those at the coarser level and, at the
// sweep's, a volume and costs of band channels each, two results and `first` (1), and a warm frame's volume and
// costs of warmBand channels where narrower. With plainFill, 8 at its level (support 6, labels 2), the planes and 1
// at level 0 (the planes' confidence). A sequence adds 6 more at level 0 (resetSequence: three states).
// rawRight is image 1's size, which may differ from image 0's (the calibration warp resamples
// it onto image 0's grid).
static unsigned long long levelFloats(const Rig& rig, const Params& params) {
  const std::vector<LevelSize> plan = pyramidPlan(rig.cam0.width, rig.cam0.height, params);
  auto pixels = [](const LevelSize& s) { return (unsigned long long)s.width * (unsigned long long)s.height; };
  unsigned long long floats = (params.lrCheck ? 10ull : 9ull) * pixels(plan[0]) +
                              (unsigned long long)rig.cam1.width * (unsigned long long)rig.cam1.height;
  if (params.plainFill)
    floats += (kPlainSupportChannels + 2ull) * pixels(plan[std::min(plan.size() - 1, size_t(params.plainFillLevel))]) +
              3ull * kMaxPlainPlanes + pixels(plan[0]);
  const unsigned long long perPixel = params.dataTerm == Params::DataTerm::Normalised ? 39 : 34;
  for (const LevelSize& size : plan) floats += perPixel * pixels(size);
  return floats;
}

unsigned long long Pipeline::bufferBytesBeforeSweep(const Rig& rig, const Params& params) {
  return levelFloats(rig, params) * sizeof(float);
}

unsigned long long Pipeline::bufferBytes(const Rig& rig, const Params& params) {
  const std::vector<LevelSize> plan = pyramidPlan(rig.cam0.width, rig.cam0.height, params);
  auto pixels = [](const LevelSize& s) { return (unsigned long long)s.width * (unsigned long long)s.height; };
  unsigned long long floats = levelFloats(rig, params);
  if (params.init == Params::Init::PlaneSweep) {
    const size_t level = size_t(sweepLevel(params, int(plan.size())));
    const bool banded = sweepBanded(params, int(plan.size()));
    for (size_t l = 0; l <= level + (banded ? 1 : 0); ++l) floats += pixels(plan[l]);
    const Eigen::Vector3d tPrime = rig.R.transpose() * rig.t;
    const int planes = sweepPlanes(levelCamera(rig.cam0, plan[level]), tPrime, params);
    if (banded) {
      const int coarsePlanes = sweepPlanes(levelCamera(rig.cam0, plan[level + 1]), tPrime, params);
      floats += (unsigned long long)(2 * coarsePlanes + 4) * pixels(plan[level + 1]);
      const int band = std::min(planes, params.initBand);
      floats += (unsigned long long)(2 * band + 5) * pixels(plan[level]);
      if (params.warmBand > 0 && params.warmBand < band) floats += 2ull * params.warmBand * pixels(plan[level]);
    } else {
      floats += (unsigned long long)(2 * planes + 4) * pixels(plan[level]);
    }
  }
  unsigned long long bytes = floats * sizeof(float);
  if (params.lrCheck)
    bytes += bufferBytes(reversedRig(rig), reverseParams(params)) -  // its grid is image 1's
             2ull * (unsigned long long)rig.cam1.width * (unsigned long long)rig.cam1.height * sizeof(float);
  return bytes;
}

// The nearest sphere: a point seen with initMaxParallaxDeg of parallax across the baseline.
double Pipeline::sweepQMax(const Eigen::Vector3d& tPrime, const Params& params) {
  return std::tan(params.initMaxParallaxDeg * M_PI / 180.0) / tPrime.norm();
}

// Enough hypotheses that neighbouring ones move no pixel by more than initPxPerPlane:
// the motion per unit of inverse depth is largest at q = 0, where it is J t' (J the
// projection's Jacobian at the ray). Fixed per rig so a moving camera never reallocates;
// the nearest sphere (qMax) follows the pose in setPose.
int Pipeline::sweepPlanes(const Camera& camera, const Eigen::Vector3d& tPrime, const Params& params) {
  const BuiltCamera cam(camera);
  const double qMax = sweepQMax(tPrime, params);
  const double cosMax = params.maxFovDeg > 0 ? std::cos(std::min(0.5 * params.maxFovDeg, 179.9) * M_PI / 180.0) : -1.0;
  double fastest = 0;  // px per unit inverse depth
  for (int y = 0; y < camera.height; y += 2)
    for (int x = 0; x < camera.width; x += 2) {
      Vec3<double> ray;
      Vec2<double> px;
      Mat23<double> J;
      if (!cam.unproject(Vec2<double>(x, y), ray) || ray.z() < cosMax || !cam.project(ray, px, &J)) continue;
      fastest = std::max(fastest, (J * tPrime).norm());
    }
  const double planes = std::ceil(qMax * fastest / params.initPxPerPlane) + 1;
  return int(std::min(double(kMaxSweepPlanes), std::max(2.0, planes)));
}

Pipeline::Pipeline(Backend& backend, const Rig& rig, const Params& params, const ImageU8& userMask, bool finishes)
    : backend_(backend), params_(params) {
  for (const LevelSize& size : pyramidPlan(rig.cam0.width, rig.cam0.height, params)) {
    Level L;
    L.size = size;
    // Fields are computed exactly at each level from the scaled cameras rather than
    // resampled from level 0: the same cost (once per pose) and no averaging of tangents.
    L.cam0 = levelCamera(rig.cam0, size);
    // Camera 1 at its own image's size at this scale (it may differ from camera 0's): its
    // fields ask whether a ray lands inside image 1.
    L.cam1 = levelCamera(rig.cam1, levelSize(rig.cam1.width, rig.cam1.height, size.scale));
    auto make = [&](int channels) { return backend_.create(size.width, size.height, channels); };
    L.userMask = make(1), L.i0 = make(1), L.i1 = make(1), L.mask = make(1), L.trajectory = make(2);
    L.tensor = make(4), L.steps = make(4), L.w = make(2), L.tangent = make(2), L.scratch = make(1);
    L.pd = {make(1), make(1), make(2), make(2), make(2), make(4)};
    L.data = {make(1), make(1), make(1)};
    if (normalising()) {
      L.n0 = make(1), L.n1 = make(1), L.moments = make(3);
    } else {
      L.n0 = L.i0, L.n1 = L.i1;
    }
    levels_.push_back(L);
  }
  if (initialising()) {
    sweep_.level = size_t(sweepLevel(params_, int(levels_.size())));
    sweep_.banded = sweepBanded(params_, int(levels_.size()));
    for (size_t l = 0; l <= sweep_.level + (sweep_.banded ? 1 : 0); ++l)
      levels_[l].confidence = backend_.create(levels_[l].size.width, levels_[l].size.height, 1);
    auto sweepAt = [&](const Level& S) {
      SweepParams p{};
      p.cam = toCameraParams(S.cam0);
      p.planes = sweepPlanes(S.cam0, rig.R.transpose() * rig.t, params_);
      p.radius = params_.initRadius;
      p.p1 = params_.initP1;
      p.p2 = params_.initP2;
      p.flatVariance = params_.noiseLevel * params_.noiseLevel;
      return p;
    };
    const Level& S = levels_[sweep_.level];
    sweep_.params = sweepAt(S);
    int channels = sweep_.params.planes;
    if (sweep_.banded) {
      const Level& C = levels_[sweep_.level + 1];
      sweep_.coarseParams = sweepAt(C);
      sweep_.params.band = channels = std::min(params_.initBand, sweep_.params.planes);
      sweep_.first = backend_.create(S.size.width, S.size.height, 1);
      sweep_.coarseVolume = backend_.create(C.size.width, C.size.height, sweep_.coarseParams.planes);
      sweep_.coarseCosts = backend_.create(C.size.width, C.size.height, sweep_.coarseParams.planes);
      sweep_.coarseBest = backend_.create(C.size.width, C.size.height, 2);
      sweep_.coarseOther = backend_.create(C.size.width, C.size.height, 2);
    }
    sweep_.volume = backend_.create(S.size.width, S.size.height, channels);
    sweep_.costs = backend_.create(S.size.width, S.size.height, channels);
    // A warm frame's band (Params::warmBand): its own volumes when narrower (a backend may
    // refuse a buffer used smaller than created).
    sweep_.warmParams = sweep_.params;
    if (sweep_.banded && params_.warmBand > 0 && params_.warmBand < channels) {
      sweep_.warmBanded = true;
      sweep_.warmParams.band = params_.warmBand;
      sweep_.warmVolume = backend_.create(S.size.width, S.size.height, params_.warmBand);
      sweep_.warmCosts = backend_.create(S.size.width, S.size.height, params_.warmBand);
    }
    sweep_.best = backend_.create(S.size.width, S.size.height, 2);
    sweep_.other = backend_.create(S.size.width, S.size.height, 2);
  }
  setUserMask(userMask);
  const int w = rig.cam0.width, h = rig.cam0.height;
  rawRight_ = backend_.create(rig.cam1.width, rig.cam1.height, 1);
  calibration_ = backend_.create(w, h, 2);
  radial_ = backend_.create(w, h, 1);
  points_ = backend_.create(w, h, 3);
  confidence_ = backend_.create(w, h, 1);
  if (params_.plainFill) {
    const Level& P = levels_[plainLevel()];
    plainSupport_ = backend_.create(P.size.width, P.size.height, kPlainSupportChannels);
    plainLabels_ = backend_.create(P.size.width, P.size.height, 2);
    plainPlanes_ = backend_.create(3 * kMaxPlainPlanes, 1, 1);
    planeConfidence_ = backend_.create(rig.cam0.width, rig.cam0.height, 1);
  }
  finishes_ = finishes;
  if (finishes_) {
    valid_ = backend_.create(w, h, 1);
    z_ = backend_.create(w, h, 1);
  }
  if (params_.lrCheck) {
    roundTripError_ = backend_.create(w, h, 1);
    reverse_ = std::make_unique<Pipeline>(backend_, reversedRig(rig), reverseParams(params_), ImageU8(), false);
    reverse_->slotBase_ = kFrameSlots / 2;  // Pipeline::recordOrReplay's layout
  }
}

void Pipeline::setUserMask(const ImageU8& userMask) {
  for (const Level& L : levels_) backend_.upload(L.userMask, levelMask(userMask, L.size).data());
}

void Pipeline::setPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  tPrime_ = R.transpose() * t;
  for (SweepParams* p : {&sweep_.params, &sweep_.coarseParams, &sweep_.warmParams}) {
    std::copy(tPrime_.data(), tPrime_.data() + 3, p->t);
    p->qMax = sweepQMax(tPrime_, params_);
  }
  FieldsParams fp{};
  Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(fp.R) = R;
  std::copy(t.data(), t.data() + 3, fp.t);
  fp.maxFovDeg = params_.maxFovDeg;
  fp.epipoleDeg = params_.epipoleDeg;
  for (size_t l = 0; l < levels_.size(); ++l) {
    Level& L = levels_[l];
    fp.cam0 = toCameraParams(L.cam0);
    fp.cam1 = toCameraParams(L.cam1);
    backend_.copy(L.mask, L.userMask);
    // Only level 0 warps image 1 by the calibration field; coarser levels borrow the
    // tangent buffer (overwritten by every warp) to receive theirs.
    backend_.fields(L.mask, l == 0 ? calibration_ : L.tangent, L.trajectory, fp);
  }
  sweepMaskPixels_ = maskPixels_ = summaryMaskPixels_ = -1;  // the mask changed: counted again when next needed
  plainRays_ = PlainRays();                                  // t' changed: made again by the next frame
  if (reverse_) reverse_->setPose(R.transpose(), -(R.transpose() * t));
  backend_.synchronize();
}

// The shares of the frame just solved, counted from the copies download() brought back
// with the results (one wait for all of them); the mask's count is read once per pose.
double Pipeline::consistentShare() const { return consistentShare_; }
double Pipeline::roundTripShare() const { return roundTripShare_; }
double Pipeline::meanConfidence() const { return meanConfidence_; }

long long Pipeline::countMask(const Buffer& mask, long long& counted) {
  if (counted < 0) {
    std::vector<float> values(mask.count());
    backend_.download(mask, values.data());
    counted = (long long)std::count_if(values.begin(), values.end(), [](float m) { return m != 0.f; });
  }
  return counted;
}

// The frame's figures, counted on the host's threads (detail::parallelPieces) over fixed
// pieces summed in order: the same value on any machine.
constexpr size_t kCountPiece = size_t(1) << 16;

template <class Predicate>
static double shareOf(const std::vector<float>& values, Predicate counts, long long maskPixels) {
  std::vector<long long> counted((values.size() + kCountPiece - 1) / kCountPiece);
  detail::parallelPieces(values.size(), kCountPiece, [&](size_t begin, size_t end) {
    counted[begin / kCountPiece] =
        std::count_if(values.begin() + ptrdiff_t(begin), values.begin() + ptrdiff_t(end), counts);
  });
  const long long total = std::accumulate(counted.begin(), counted.end(), 0LL);
  return maskPixels ? double(total) / double(maskPixels) : 0.0;
}

// Four running sums a piece: one would be a chain of dependent additions (the compiler may
// not reorder floating-point sums), four times slower on every warm frame's read.
static double sumOf(const std::vector<float>& values) {
  std::vector<double> sums((values.size() + kCountPiece - 1) / kCountPiece);
  detail::parallelPieces(values.size(), kCountPiece, [&](size_t begin, size_t end) {
    double lanes[4] = {0, 0, 0, 0};
    size_t i = begin;
    for (; i + 4 <= end; i += 4)
      for (size_t k = 0; k < 4; ++k) lanes[k] += values[i + k];
    for (; i < end; ++i) lanes[0] += values[i];
    sums[begin / kCountPiece] = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
  });
  return std::accumulate(sums.begin(), sums.end(), 0.0);
}

void Pipeline::stage(const char* name) {
  if (profiling_) backend_.beginStage(name);
}

// Float images are checked for NaN and infinities as they are copied (Backend::upload),
// not in a pass of their own: at 30 fps a frame's images are new to the cache, and reading
// them twice costs a tenth of a warm frame.
void Pipeline::upload(const InputImage& left, const InputImage& right) {
  stage("upload");
  uploadImage(levels_[0].i0, left, "left");
  uploadImage(rawRight_, right, "right");
}

void Pipeline::uploadImage(const Buffer& dst, const InputImage& image, const char* side) {
  if (image.bytes) return backend_.uploadBytes(dst, image.bytes);
  bool finite = true;
  backend_.upload(dst, image.floats, &finite);
  if (!finite) throw Error(std::string(side) + " image contains NaN or infinite pixels");
}

// lrCheck: the other direction's inputs are this one's, swapped, copied on the device.
void Pipeline::swapIntoReverse() {
  backend_.copy(reverse_->levels_[0].i0, rawRight_);
  backend_.copy(reverse_->rawRight_, levels_[0].i0);
}

// The images of levels 0 .. count - 1 (a warm frame never visits the coarser ones).
void Pipeline::buildPyramid(size_t count) {
  stage("calibration warp");
  backend_.warp(levels_[0].i1, rawRight_, calibration_);
  stage("pyramid");
  for (size_t l = 1; l < count; ++l) {
    backend_.downsample(levels_[l].i0, levels_[l - 1].i0, float(params_.scale));
    backend_.downsample(levels_[l].i1, levels_[l - 1].i1, float(params_.scale));
  }
  if (!normalising()) return;
  // Each level normalised from its own grey levels, in a window of the same size in that
  // level's pixels: normalising once at full resolution and then downsampling would
  // average the zero-mean fine texture away and starve the coarse levels.
  stage("normalise");
  const NormaliseParams np = normaliseParams(params_);
  for (size_t l = 0; l < count; ++l) {
    Level& L = levels_[l];
    backend_.normalise(L.n0, L.moments, L.i0, L.mask, np);
    backend_.normalise(L.n1, L.moments, L.i1, L.mask, np);
  }
}

// Params::edgeUpsample: coarse neighbours a pixel or more apart straddle a depth edge (0.5
// measured the same), and a 5x5 window tells the surfaces apart where 3x3 is swayed by
// texture (CPU oracle, clean binocular tau>1 4.9 against 5.0 %).
constexpr float kEdgeUpsamplePx = 1.f;
constexpr int kEdgeUpsampleRadius = 2;

// Level l's estimate from the level above (zero at the coarsest), resampled without blending
// surfaces across depth edges (Params::edgeUpsample), and the sweep's confidence below it.
void Pipeline::startFromCoarser(size_t l) {
  Level& L = levels_[l];
  if (l + 1 == levels_.size()) {
    backend_.fill(L.pd.u, 0.f);
    backend_.fill(L.w, 0.f);
    return;
  }
  const Level& coarse = levels_[l + 1];
  const float s = float(params_.scale);
  if (params_.edgeUpsample) {
    backend_.upsampleEstimate(L.pd.u, L.w, coarse.pd.u, coarse.w, L.n0, L.n1, L.mask,
                              {s, kEdgeUpsamplePx, kEdgeUpsampleRadius});
  } else {
    backend_.upsample(L.pd.u, coarse.pd.u, s, s);
    backend_.upsample(L.w, coarse.w, s, s);
  }
  if (initialising() && l < sweep_.level) backend_.upsample(L.confidence, coarse.confidence, s, 1.f);
}

void Pipeline::initialiseLevel(size_t l) {
  Level& L = levels_[l];
  stage("structure tensor");
  const TensorParams tp{params_.beta, params_.eta, params_.wMin, params_.tensorSigma, params_.alpha0, params_.alpha1};
  backend_.structureTensor(L.tensor, L.steps, L.i0, L.mask, tp);
  // A warm frame's band sweep coarse level is initialised by the carried estimate instead
  // of the full sweep; the pixels its check rejects keep the coarser levels' estimate,
  // where a warm frame solved them (Params::warmCoarseWarps).
  const bool carried = warmFrame_ && sweep_.banded && l == sweep_.level + 1;
  stage("upsample");
  // With the coarser levels skipped (warmCoarseWarps 0), rejected pixels keep the last
  // frame's values here.
  const bool coarserSkipped = carried && params_.warmCoarseWarps == 0;
  if (!coarserSkipped) startFromCoarser(l);
  if (carried) carryIntoCoarseSweep();
  if (!carried && initialising() && sweep_.banded && l == sweep_.level + 1) runCoarseSweep();
  if (initialising() && l == sweep_.level) runSweep();
  for (const Buffer* b : {&L.pd.v, &L.pd.p, &L.pd.q}) backend_.fill(*b, 0.f);
}

// The sweep proposes, the left-right check decides: pixels it matches consistently (near
// objects, large motion) take its disparity; the rest keep the coarse-to-fine estimate,
// which is smooth and, where a near object was lost, lies on the background (the right
// value for the occluded band beside it). Both views are swept on the calibrated images (image 1 has camera 0's model
// and orientation there, so the sweep needs one camera and the translation only): camera 0 against image 1 with t',
// then camera 1 against image 0 with -t' for the left-right check.
//
// With a band, the full sweep runs one level coarser (a quarter of the pixels, half the
// hypotheses), is checked there and initialises that level too (its confident pixels then
// start the coarser level's warps from the sweep instead of the coarse-to-fine estimate);
// the sweep level then scores p.band hypotheses a pixel around its winners: an eighth of
// the full sweep's work or less. Measured on the 12 development pairs (CPU, band 16):
// initialising the coarser level too moved the T265-like forward pairs' non-occluded
// tau>1 from 19.9 to 17.8 % and changed the binocular pairs by 0.1 point.
void Pipeline::runCoarseSweep() {
  Level& C = levels_[sweep_.level + 1];
  fullSweep(C, sweep_.coarseParams, sweep_.coarseVolume, sweep_.coarseCosts, sweep_.coarseBest, sweep_.coarseOther);
  checkSweep(C, sweep_.coarseParams, sweep_.coarseBest, sweep_.coarseOther);
}

void Pipeline::runSweep() {
  Level& L = levels_[sweep_.level];
  if (sweep_.banded) {
    const Level& C = levels_[sweep_.level + 1];
    const float coarseScale = float(C.size.scale / L.size.scale);
    if (warmFrame_ && sweep_.warmBanded)
      bandSweep(L, sweep_.coarseBest, sweep_.coarseOther, coarseScale, sweep_.warmParams, sweep_.warmVolume,
                sweep_.warmCosts);
    else
      bandSweep(L, sweep_.coarseBest, sweep_.coarseOther, coarseScale, sweep_.params, sweep_.volume, sweep_.costs);
  } else {
    fullSweep(L, sweep_.params, sweep_.volume, sweep_.costs, sweep_.best, sweep_.other);
  }
  checkSweep(L, sweep_.params, sweep_.best, sweep_.other);
}

// The left-right check of a level's two sweeps, which initialises that level.
void Pipeline::checkSweep(Level& L, const SweepParams& p, const Buffer& best, const Buffer& other) {
  stage("sweep: check");
  backend_.sweepInitialise(L.pd.u, L.w, L.confidence, best, other, L.mask, p,
                           {params_.lrTolerancePx, params_.initAccept, params_.initMaxCost});
}

// Reverses a sweep's translation: the other view as the reference.
static SweepParams reversed(SweepParams p) {
  for (double& c : p.t) c = -c;
  return p;
}

void Pipeline::fullSweep(const Level& L, const SweepParams& p, const Buffer& volume, const Buffer& costs,
                         const Buffer& best, const Buffer& other) {
  // The volume of warped samples becomes the aggregated costs once the costs are taken.
  auto sweep = [&](const Buffer& result, const Buffer& reference, const Buffer& image, const SweepParams& q) {
    stage("sweep: warp");
    backend_.sweepWarp(volume, image, L.mask, q);
    stage("sweep: cost");
    backend_.sweepCost(costs, reference, volume, L.mask, q);
    stage("sweep: aggregate");
    backend_.sweepAggregate(volume, costs, L.mask, q);
    stage("sweep: select");
    backend_.sweepSelect(result, volume, costs, L.mask, q);
  };
  sweep(best, L.i0, L.i1, p);
  sweep(other, L.i1, L.i0, reversed(p));
}

void Pipeline::bandSweep(const Level& L, const Buffer& coarseBest, const Buffer& coarseOther, float coarseScale,
                         const SweepParams& p, const Buffer& volume, const Buffer& costs) {
  auto sweep = [&](const Buffer& result, const Buffer& proposal, const Buffer& reference, const Buffer& image,
                   const SweepParams& q) {
    stage("sweep: band warp");
    backend_.sweepBandWarp(volume, sweep_.first, image, proposal, L.mask, q, coarseScale);
    stage("sweep: band cost");
    backend_.sweepBandCost(costs, reference, volume, sweep_.first, L.mask, q);
    stage("sweep: band aggregate");
    backend_.sweepBandAggregate(volume, costs, sweep_.first, L.mask, q);
    stage("sweep: band select");
    backend_.sweepBandSelect(result, volume, costs, sweep_.first, L.mask, q);
  };
  sweep(sweep_.best, coarseBest, L.i0, L.i1, p);
  sweep(sweep_.other, coarseOther, L.i1, L.i0, reversed(p));
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

// `warps` (at least one: Params::validate) in the coarse kernels backends may fuse
// (backend.hpp): a warp's iterations, then its tail, which also makes the next warp's data
// term. Timing stages separately, the tail is issued as its fine kernels with a stage
// boundary between them.
void Pipeline::solveLevel(Level& L, int warps, const std::function<void(int)>& warpDone) {
  const PrimalDualParams pdParams = primalDualParams();
  // A floor of 1 weighs every pixel 1: then the kernel need not read the confidence.
  const Buffer weight = params_.occlusionWeight < 1.f ? L.confidence : Buffer{};
  const WarpBuffers warp{L.pd.u, L.w,  L.tangent,    L.mask, L.data,
                         L.n0,   L.n1, L.trajectory, weight, params_.occlusionWeight};
  const Buffer medianScratch = params_.medianFilter ? L.scratch : Buffer{};
  auto derivatives = [&] {
    stage("warp derivatives");
    backend_.warpDerivatives(warp.data, warp.tangent, warp.i0, warp.i1, warp.trajectory, warp.w, warp.u, warp.mask,
                             warp.confidence, warp.weightFloor);
  };
  derivatives();
  for (int n = 0; n < warps; ++n) {
    const bool nextWarp = n + 1 < warps;
    stage("primal-dual");
    backend_.warpIterations(L.pd, L.data, L.tensor, L.steps, L.mask, pdParams);
    if (!profiling_) {
      backend_.warpTail(warp, medianScratch, params_.duMax, nextWarp);
    } else {
      if (params_.medianFilter) {
        stage("median");
        backend_.median(L.scratch, L.pd.u, L.mask);
        backend_.copy(L.pd.u, L.scratch);
      }
      stage("accumulate");
      backend_.accumulate(L.pd.u, L.w, L.data.u0, L.tangent, L.mask, params_.duMax);
      if (nextWarp) derivatives();
    }
    warpDone(n);
  }
}

// The warm start: the previous frame's state, carried into this frame's view of camera 0
// and of camera 1' (the sweep's other view), stands in for the full sweep one level above
// the band's: its left-right check initialises that level, and the band sweep below
// searches around it. A few fixed-point steps find where each pixel's point was.
constexpr int kCarrySteps = 3;

void Pipeline::carryIntoCoarseSweep() {
  Level& C = levels_[sweep_.level + 1];
  stage("carry");
  CarryParams p{toCameraParams(levels_[0].cam0), toCameraParams(C.cam0), {0, 0, 0}, kCarrySteps};
  backend_.carryEstimate(sweep_.coarseBest, state_, Buffer{}, motion_, C.mask, p);
  std::copy(tPrime_.data(), tPrime_.data() + 3, p.extraT);
  backend_.carryEstimate(sweep_.coarseOther, state_, Buffer{}, motion_, C.mask, p);
  checkSweep(C, sweep_.coarseParams, sweep_.coarseBest, sweep_.coarseOther);
}

void Pipeline::triangulate() {
  stage("triangulate");
  const double tp[3] = {tPrime_.x(), tPrime_.y(), tPrime_.z()};
  backend_.triangulate(radial_, points_, levels_[0].w, levels_[0].mask, toCameraParams(levels_[0].cam0), tp);
}

// The result's confidence (backend.hpp resultConfidence). The structure term's window is
// 7x7 full-resolution pixels: wide enough that the Cramer-Rao deviation averages a few
// texture cycles, narrow enough that a plain surface a few pixels from an edge is still
// recognised as plain. It is 1/2 where that deviation is half a pixel (the tau>1 threshold
// is one). The photometric term compares the normalised images (units of the local
// contrast, where noise on texture is a few tenths and a wrong match about one) or, with
// the brightness data term, grey levels (a few times the noise).
constexpr int kConfidenceRadius = 3;
constexpr float kConfidenceSigmaPx = 0.5f;
constexpr float kNormalisedResidualScale = 0.6f;
constexpr float kBrightnessResidualNoises = 4.f;

// The confidence terms without what rejects pixels (round trip, floors, infinity): the
// measurement model of the temporal filter, before the result's own confidence.
ConfidenceParams Pipeline::confidenceTerms() const {
  ConfidenceParams p{};
  p.radius = kConfidenceRadius;
  p.noise = params_.noiseLevel;
  p.sigmaPx = kConfidenceSigmaPx;
  p.residualScale = normalising() ? kNormalisedResidualScale : kBrightnessResidualNoises * params_.noiseLevel;
  p.roundTripPx = params_.lrCheckPx;
  return p;
}

// The temporal filter's measurement model, in px of disparity at full resolution: a pixel
// of full confidence is good to about half a pixel (the realtime preset's tau>1 is ~5 % on
// the pixels the sweep's check trusts), the deviation growing as its confidence falls
// (floored, so the least confident pixel still counts a little); a static surface carried
// by the motion may move by a tenth of a pixel a frame (the nearest-pixel lookup of
// carryEstimate). The confidence is this frame's estimate's own (structure along the
// curve, photometric agreement, the sweep's check), not the sweep's check alone: on a
// plain surface the check passes a carried estimate that the image cannot confirm, and
// there the prior should weigh more. Measured on seqD1 (CPU, warm, 16 frames; with the
// sweep's confidence): clean tau>1 26.69 % (26.94), flicker 2.01 % (2.02); T265-like 30.67
// % (33.07), flicker 10.89 % (13.34), moving box 12.83 % (15.61).
constexpr float kMeasurementPx = 0.5f;
constexpr float kDriftPx = 0.1f;
constexpr float kConfidenceFloor = 0.1f;

void Pipeline::filterResult() {
  Level& L0 = levels_[0];
  stage("temporal filter");
  backend_.resultConfidence(confidence_, radial_, points_, L0.i0, L0.n0, L0.n1, L0.w, L0.trajectory,
                            initialising() ? L0.confidence : Buffer{}, Buffer{}, planeConfidence_, L0.mask,
                            confidenceTerms());
  const CameraParams cam = toCameraParams(L0.cam0);
  backend_.carryEstimate(prior_, state_, radial_, motion_, L0.mask, {cam, cam, {0, 0, 0}, 1});
  TemporalParams tp{cam,
                    {tPrime_.x(), tPrime_.y(), tPrime_.z()},
                    params_.temporalStrength,
                    params_.temporalGate,
                    kMeasurementPx,
                    kDriftPx,
                    kConfidenceFloor};
  backend_.temporalFilter(next_, L0.pd.u, L0.w, prior_, radial_, points_, confidence_, L0.mask, tp);
}

void Pipeline::finishResult() {
  Level& L0 = levels_[0];
  if (reverse_) {
    stage("round trip");
    const Pipeline& r = *reverse_;
    backend_.roundTrip(roundTripError_, L0.w, calibration_, r.levels_[0].w, r.calibration_, r.levels_[0].mask, L0.mask);
  }
  stage("confidence");
  ConfidenceParams p = confidenceTerms();
  p.roundTripMaxPx = params_.lrCheckPx;
  p.infinityPx = params_.infinityPx;
  p.infinityBoundPx = params_.infinityBoundPx;
  p.invalidBelow = params_.rejectBelow;
  p.maxDeviationPx = params_.maxDeviationPx;
  backend_.resultConfidence(confidence_, radial_, points_, L0.i0, L0.n0, L0.n1, L0.w, L0.trajectory,
                            initialising() ? L0.confidence : Buffer{}, reverse_ ? roundTripError_ : Buffer{},
                            planeConfidence_, L0.mask, p);
}

// The level whose size the confidence is summarised at: a sixteenth of the pixels with the
// usual factor 2, enough for a mean, and a small transfer.
static size_t summaryLevel(size_t levels) { return std::min<size_t>(2, levels - 1); }

// Before finishOutputs, which makes the confidence NaN where unsolved: here it is 0 there,
// and outside the field of view. The decimation blends the rim with those zeros, alike in
// every frame, so means of one sequence compare.
void Pipeline::summariseConfidence() {
  const Level& S = levels_[summaryLevel(levels_.size())];
  stage("confidence");
  backend_.downsample(confidenceSummary_, confidence_, float(levels_[0].size.scale / S.size.scale));
}

// In place on the solver's disparity and warp at level 0: nothing reads them after the
// frame (a sequence carries its own state, filterResult's, and the next frame starts them
// afresh), and a NaN there is what the user must see.
void Pipeline::finishOutputs() {
  Level& L0 = levels_[0];
  stage("finish");
  backend_.finishResult(valid_, z_, radial_, points_, L0.pd.u, L0.w, confidence_);
}

void Pipeline::issueSolve(const std::function<void(double)>& progress, FrameKind kind) {
  // Progress in pixel-warps: a warp costs about the same per pixel at every level, and the
  // plane sweep about kSweepWarpsPerPlane warps per pixel and hypothesis (measured at full
  // resolution with 262 hypotheses: 2x the level's 30 warps on the CPU, 3x with CUDA).
  constexpr double kSweepWarpsPerPlane = 0.25;
  auto pixels = [](const Level& L) { return double(L.size.width) * L.size.height; };
  double sweepWork = 0.0, coarseSweepWork = 0.0;
  if (initialising() && sweep_.banded) {
    coarseSweepWork = pixels(levels_[sweep_.level + 1]) * sweep_.coarseParams.planes * kSweepWarpsPerPlane;
    sweepWork = pixels(levels_[sweep_.level]) * sweep_.params.band * kSweepWarpsPerPlane;
  } else if (initialising()) {
    sweepWork = pixels(levels_[sweep_.level]) * sweep_.params.planes * kSweepWarpsPerPlane;
  }
  // A warm frame replaces the full sweep by the carried estimate and solves the levels
  // above it with Params::warmCoarseWarps warps each (docs/sequences.md has the measurements).
  const bool warm = kind.warm && canWarmStart();
  warmFrame_ = warm;
  const size_t levels = warm && params_.warmCoarseWarps == 0 ? sweep_.level + 2 : levels_.size();
  if (warm) coarseSweepWork = 0;
  double total = sweepWork + coarseSweepWork, done = 0;
  const std::vector<int> warps = warpSchedule(params_, int(levels_.size()), warm);
  for (size_t l = 0; l < levels; ++l) total += pixels(levels_[l]) * warps[l];
  auto advance = [&](double work) {
    done += work;
    if (progress) progress(std::min(1.0, done / total));
  };
  buildPyramid(levels);
  for (size_t l = levels; l-- > 0;) {
    initialiseLevel(l);
    if (initialising() && sweep_.banded && l == sweep_.level + 1) advance(coarseSweepWork);
    if (initialising() && l == sweep_.level) advance(sweepWork);
    solveLevel(levels_[l], warps[l], [&](int) { advance(pixels(levels_[l])); });
  }
  if (fillsPlains()) findPlainSupport();
}

// Plain regions (Params::plainFill, docs/confidence.md "Plain surfaces"): the solve's own
// confidence (without what rejects pixels) picks, under each pixel of the plain-fill level,
// the full-resolution pixel whose warp the host's plane fits may trust.
void Pipeline::findPlainSupport() {
  Level& L0 = levels_[0];
  triangulate();
  stage("plain fill: support");
  backend_.resultConfidence(confidence_, radial_, points_, L0.i0, L0.n0, L0.n1, L0.w, L0.trajectory,
                            initialising() ? L0.confidence : Buffer{}, Buffer{}, Buffer{}, L0.mask, confidenceTerms());
  const Level& P = levels_[plainLevel()];
  backend_.plainSupport(plainSupport_, confidence_, L0.w, L0.mask, P.i0, P.mask);
}

// The host's part: the plain regions of the level's image and the planes their borders
// agree on, uploaded for fillPlanes (the frame waits for the solve here, once).
void Pipeline::planPlainFill() {
  stage("plain fill: planes");
  const Level& P = levels_[plainLevel()];
  const size_t n = size_t(P.size.width) * P.size.height;
  support_.resize(kPlainSupportChannels * n);
  backend_.download(plainSupport_, support_.data());
  PlainFillParams p;
  p.noise = float(params_.noiseLevel * P.size.scale);  // the level averages at least 1 / scale^2 pixels
  p.qMax = sweepQMax(tPrime_, params_);
  p.confidenceSigmaPx = kConfidenceSigmaPx;
  if (plainRays_.ray.empty()) plainRays_ = plainRays(levels_[0].cam0, tPrime_, P.size.width, P.size.height);
  const PlainPlanes found =
      findPlainPlanes(plainRays_, levels_[0].cam0, tPrime_, P.size.width, P.size.height, support_, p);
  std::vector<float> planes(3 * kMaxPlainPlanes, 0.f);
  for (size_t k = 0; k < found.planes.size(); ++k)
    for (int c = 0; c < 3; ++c) planes[3 * k + size_t(c)] = found.planes[k][c];
  backend_.upload(plainLabels_, found.labels.data());
  backend_.upload(plainPlanes_, planes.data());
}

void Pipeline::issueFinish(FrameKind kind) {
  if (fillsPlains()) {
    stage("plain fill");
    const Level& L0 = levels_[0];
    const double tp[3] = {tPrime_.x(), tPrime_.y(), tPrime_.z()};
    backend_.fillPlanes(L0.pd.u, L0.w, planeConfidence_, plainLabels_, plainPlanes_, L0.mask, toCameraParams(L0.cam0),
                        tp);
  }
  triangulate();
  if (kind.filter) filterResult();
  finishResult();
  if (summarises(kind)) summariseConfidence();
  if (finishes_) finishOutputs();
}

// Straight into the result's images: a warp pixel is two floats and a point three, laid
// out as the backend's 2- and 3-channel buffers.
static_assert(sizeof(Vec2f) == 2 * sizeof(float) && std::is_standard_layout_v<Vec2f>, "Vec2f must be 2 floats");
static_assert(sizeof(Point3f) == 3 * sizeof(float) && std::is_standard_layout_v<Point3f>, "Point3f must be 3 floats");

// The valid mask from the finished radial depth (NaN exactly where unsolved), so that it
// need not be downloaded: a branch-free loop the compiler vectorises, in pieces across the
// host's threads (on one, it and the check's counts took 0.4 ms of a 2.6 ms warm frame on
// the H200's host).
static void validFromRadial(DepthResult& out) {
  const float* __restrict radial = out.depth.radial.data.data();
  uint8_t* __restrict valid = fitImage(out.valid, out.depth.radial.width, out.depth.radial.height);
  detail::parallelPieces(out.depth.radial.size(), kCountPiece, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) valid[i] = uint8_t(radial[i] == radial[i]);
  });
}

// One downloadAll for the frame: the selected results and, where asked, the buffers its
// shares are counted from.
void Pipeline::download(DepthResult& out, bool countConsistent, bool countConfidence) {
  stage("download");
  const Level& L0 = levels_[0];
  const int w = L0.size.width, h = L0.size.height;
  std::vector<Backend::Download> list{{radial_, fitImage(out.depth.radial, w, h)}};
  // An unselected output becomes an empty image. Every image's pixels are floats (a warp
  // pixel two, a point three), so the cast only names them so.
  auto select = [&](bool selected, const Buffer& src, auto& image) {
    if (selected)
      list.push_back({src, reinterpret_cast<float*>(fitImage(image, w, h))});
    else
      image = std::decay_t<decltype(image)>();
  };
  select(selection_.confidence, confidence_, out.confidence);
  select(selection_.disparity, L0.pd.u, out.disparity);
  select(selection_.warp, L0.w, out.warp);
  select(selection_.points, points_, out.depth.points);
  select(selection_.points, z_, out.depth.z);
  countConsistent = countConsistent && initialising();
  if (countConsistent) {
    const Level& S = levels_[sweep_.level];
    countMask(S.mask, sweepMaskPixels_);
    sweepConfidence_.resize(S.confidence.count());
    list.push_back({S.confidence, sweepConfidence_.data()});
  }
  if (reverse_) {
    countMask(L0.mask, maskPixels_);
    roundTripErrors_.resize(roundTripError_.count());
    list.push_back({roundTripError_, roundTripErrors_.data()});
  }
  if (countConfidence) {
    countMask(levels_[summaryLevel(levels_.size())].mask, summaryMaskPixels_);
    confidenceSummaries_.resize(confidenceSummary_.count());
    list.push_back({confidenceSummary_, confidenceSummaries_.data()});
  }
  backend_.downloadAll(list);
  validFromRadial(out);
  const float accept = params_.initAccept, limit = params_.lrCheckPx;
  consistentShare_ = countConsistent ? shareOf(
                                           sweepConfidence_, [&](float c) { return c >= accept; }, sweepMaskPixels_)
                                     : std::numeric_limits<double>::quiet_NaN();
  roundTripShare_ = reverse_ ? shareOf(
                                   roundTripErrors_, [&](float e) { return e <= limit; }, maskPixels_)
                             : std::numeric_limits<double>::quiet_NaN();
  meanConfidence_ = countConfidence && summaryMaskPixels_ > 0 ? sumOf(confidenceSummaries_) / double(summaryMaskPixels_)
                                                              : std::numeric_limits<double>::quiet_NaN();
}

// Slots: slotBase_ + a kind's slot for the solve, and kKindSlots more for the finish after
// the host's plain fill (without it, the whole frame is the first).
constexpr int kKindSlots = 4;

void Pipeline::recordOrReplay(int slot, const std::function<void(double)>& progress,
                              const std::function<void()>& issue) {
  if (!profiling_ && backend_.canReplayFrame(slot)) {
    // A replayed frame issues nothing the warps could report: its start and, once its
    // results are here, its end.
    if (progress) progress(0.0);
    backend_.replayFrame(slot);
  } else {
    backend_.beginFrame(slot);
    issue();
    backend_.endFrame();
  }
}

void Pipeline::issueOrReplay(const std::function<void(double)>& progress, FrameKind kind) {
  if (kind.filter && state_.id < 0) throw Error("pipeline: a filtered frame before resetSequence()");
  const int slot = slotBase_ + kind.slot();
  if (!fillsPlains()) {
    recordOrReplay(slot, progress, [&] {
      issueSolve(progress, kind);
      issueFinish(kind);
    });
    return;
  }
  recordOrReplay(slot, progress, [&] { issueSolve(progress, kind); });
  planPlainFill();
  recordOrReplay(slot + kKindSlots, nullptr, [&] { issueFinish(kind); });
}

void Pipeline::resetSequence() {
  if (state_.id < 0) {
    const Level& L0 = levels_[0];
    state_ = backend_.create(L0.size.width, L0.size.height, 2);
    next_ = backend_.create(L0.size.width, L0.size.height, 2);
    prior_ = backend_.create(L0.size.width, L0.size.height, 2);
    motion_ = backend_.create(kMotionFloats, 1, 1);
    const LevelSize& S = levels_[summaryLevel(levels_.size())].size;
    confidenceSummary_ = backend_.create(S.width, S.height, 1);
  }
  backend_.fill(state_, -1.f);
}

void Pipeline::setMotion(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  if (motion_.id < 0) throw Error("pipeline: setMotion before resetSequence()");
  float m[kMotionFloats];
  for (int i = 0; i < 9; ++i) m[i] = float(R(i / 3, i % 3));
  for (int i = 0; i < 3; ++i) m[9 + i] = float(t[i]);
  backend_.upload(motion_, m);
}

void Pipeline::commitSequenceFrame() { backend_.copy(state_, next_); }

void Pipeline::run(const InputImage& left, const InputImage& right, bool profile,
                   const std::function<void(double)>& progress, DepthResult& out, FrameKind kind,
                   bool countConsistent) {
  profiling_ = profile;
  upload(left, right);
  if (reverse_) {
    // The other direction first: the round trip at the end of this frame reads its result.
    reverse_->profiling_ = profile;
    swapIntoReverse();
    reverse_->issueOrReplay(nullptr, {});
  }
  const bool replay = !profiling_ && backend_.canReplayFrame(slotBase_ + kind.slot());
  issueOrReplay(progress, kind);
  download(out, countConsistent, countConsistent && summarises(kind));
  if (replay && progress) progress(1.0);
  if (profiling_)
    out.stages = backend_.takeStageTimes();
  else
    out.stages.clear();
}

detail::DeviceIO Pipeline::deviceIO() const {
  const Level& L0 = levels_[0];
  return {L0.i0, rawRight_, valid_, L0.pd.u, L0.w, radial_, points_, z_, confidence_};
}

void Pipeline::runOnDevice(FrameKind kind) {
  profiling_ = false;
  if (reverse_) {
    reverse_->profiling_ = false;
    swapIntoReverse();
    reverse_->issueOrReplay(nullptr, {});
  }
  issueOrReplay(nullptr, kind);
}

}  // namespace cs

// The kernels every backend implements. The pipeline (core/src/pipeline.cpp) is the
// only caller; it is written once against this interface. The contracts are checked here,
// above the backends (Backend's public methods), once for all of them. Internal: not
// installed; only the library's own targets and its tests see core/internal.
//
// Buffers are 2-D arrays of `channels` interleaved floats owned by the backend.
// Backends may enqueue work (GPU) or run it at once (CPU); download() and
// synchronize() wait for completion.
#pragma once
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "curvestereo/kernel_params.hpp"
#include "curvestereo/timing.hpp"

namespace cs {

struct Buffer {
  int id = -1;
  int width = 0;
  int height = 0;
  int channels = 0;
  size_t count() const { return size_t(width) * size_t(height) * size_t(channels); }
};

// The primal and dual variables of the anisotropic TGV-L1 problem at one level.
struct PrimalDualBuffers {
  Buffer u, uBar;  // 1 ch: disparity along the curve (px of the level)
  Buffer v, vBar;  // 2 ch: the TGV auxiliary field
  Buffer p;        // 2 ch: dual of alpha1 (D grad u - v)
  Buffer q;        // 4 ch: dual of alpha0 grad v
};

// The linearised data term rho(u) = iz + (u - u0) * iu, valid where mask is set.
struct DataTermBuffers {
  Buffer u0;  // 1 ch: u at the start of the warp
  Buffer iu;  // 1 ch: derivative of I1 along the curve
  Buffer iz;  // 1 ch: I1(x + w) - I0(x)
};

struct PrimalDualParams : PrimalDualWeights {
  std::vector<PrimalDualStep> schedule;  // one entry per iteration
};

// Recorded frames a backend keeps (beginFrame): 4 kinds x 2 parts (the solve, and the finish
// after the host's plain fill) x 2 directions (lrCheck).
constexpr int kFrameSlots = 16;

// The normalised Gaussian taps of standard deviation sigma > 0 over radius ceil(3 sigma)
// (2 radius + 1 of them, the middle one at offset 0): the one definition behind the
// structure tensor's smoothing on every backend and normaliseParams().
std::vector<float> gaussianTaps(float sigma);

// One warp's buffers at a level (docs/design.md "Per frame" 3.4), as warpTail() takes them: the
// estimate, the tangent, the data term and what warpDerivatives() reads to make it.
struct WarpBuffers {
  Buffer u, w, tangent, mask;  // 1, 2, 2, 1 ch
  DataTermBuffers data;
  Buffer i0, i1, trajectory;  // 1, 1, 2 ch
  Buffer confidence;          // 1 ch; id -1 = none
  float weightFloor;
};

// The kernels. Each public method checks its arguments against the contract written
// beside it (every buffer created by this backend and used no larger than created, the
// channels and sizes named, parameters in range) and throws cs::Error with one line
// naming the kernel and the problem; then it calls the protected virtual of the same
// name with a "do" prefix, which a backend implements knowing its arguments are valid.
// The backends' copies between the caller's memory and staging memory, split across the
// host's threads (detail::parallelFor). copyFloats: n floats; with `finite`, also whether
// all of them were finite, in the same pass (no extra read of a large image).
void copyBytes(void* dst, const void* src, size_t bytes);
void copyFloats(float* dst, const float* src, size_t n, bool* finite);
// The byte upload's conversion on the host: dst[i] = unitFromByte(src[i]).
void floatsFromBytes(float* dst, const uint8_t* src, size_t n);

class Backend {
 public:
  virtual ~Backend() = default;
  virtual std::string name() const = 0;    // "cpu", "cuda", "vulkan"
  virtual std::string device() const = 0;  // human-readable device description
  // Memory the backend's buffers may use, in bytes (0 = unknown). Stereo refuses a frame
  // whose buffers need more, with an error naming the size, before allocating any.
  virtual unsigned long long memoryBytes() const { return 0; }

  // --- memory ---
  // width, height, channels > 0. A buffer is used with the shape it was created with; the
  // contract refuses a larger one, and a backend may take a smaller one (fewer floats) as a
  // view of its start (CPU, Vulkan: the tests' guard buffers) or refuse it (CUDA, which
  // trades buffers' memory within a frame).
  Buffer create(int width, int height, int channels);
  // finite (optional): set to whether every value was finite (NaN and +-inf are not), found
  // in the copy's own pass: Stereo's input check at no extra read of the image.
  void upload(const Buffer& dst, const float* host, bool* finite = nullptr);
  // dst.count() 8-bit samples, stored as unitFromByte(v): a camera's 8-bit image uploaded
  // as it is, a quarter of the floats' bytes, converted where the backend's memory is.
  void uploadBytes(const Buffer& dst, const uint8_t* host);
  void download(const Buffer& src, float* host);
  // Several downloads with one wait: a frame's results come back together, where one
  // download() each waits once each (a round trip to the device per buffer).
  struct Download {
    Buffer src;
    float* host;
  };
  void downloadAll(const std::vector<Download>& downloads);
  void fill(const Buffer& dst, float value);
  void copy(const Buffer& dst, const Buffer& src);  // the same number of floats

  // --- kernels (one file / shader per stage in each backend) ---
  // Unless said otherwise, the buffers of one call have the same width and height.
  // Per rig (or per pose): mask (1 ch; in: non-zero where allowed, out: 1 where allowed
  // and valid, else 0), calibration field (2 ch) and trajectory field (2 ch), on the grid
  // of params.cam0 (its width and height are the buffers').
  void fields(const Buffer& mask, const Buffer& calibration, const Buffer& trajectory, const FieldsParams& params);
  // dst(x) = src(x + flow(x)), bilinear, clamped to the image edge. flow (2 ch) has dst's
  // size, src dst's channels and any size.
  void warp(const Buffer& dst, const Buffer& src, const Buffer& flow);
  // dst = src smoothed and decimated by `scale` (> 0; pixel-centre aware); same channels.
  void downsample(const Buffer& dst, const Buffer& src, float scale);
  // dst = valueScale * src resampled bilinearly to dst's (finer) grid; same channels.
  void upsample(const Buffer& dst, const Buffer& src, float scale, float valueScale);
  // The estimate one level finer. u = scale coarseU and w = scale coarseW, resampled
  // bilinearly as upsample(); but where the coarse pixels around a masked fine pixel,
  // (ix, iy), (ix + 1, iy), (ix, iy + 1), (ix + 1, iy + 1) (ix = floor of its coarse x,
  // clamped to [0, coarse width - 2]; iy alike), span scale * coarseU >= p.edge, bilinear
  // resampling would invent disparities between two surfaces. There the pixel takes the u
  // and w of the neighbour whose displacement matches best: the least sum over the window
  // offsets (dy, then dx, each -radius..radius) of |n0(q) - bilinear n1(q + scale coarseW)|,
  // q the offset pixel clamped to the image; the first in that order on ties. u, mask, n0,
  // n1 1 ch, w 2 ch on the fine grid; coarseU 1 ch, coarseW 2 ch on a coarse grid >= 2x2.
  void upsampleEstimate(const Buffer& u, const Buffer& w, const Buffer& coarseU, const Buffer& coarseW,
                        const Buffer& n0, const Buffer& n1, const Buffer& mask, const EstimateUpsampleParams& p);
  // dst = (src - m) / sqrt(v + epsilon^2), with m and v the mean and variance of src over
  // the masked pixels of a Gaussian window (weights taps(dx) taps(dy), pixels outside the
  // image skipped); 0 outside the mask. moments (3 ch) is scratch: the horizontal pass's
  // sums of weight, weight src and weight src^2 over masked pixels. dst, src, mask 1 ch;
  // 0 <= params.radius <= kMaxNormaliseRadius.
  void normalise(const Buffer& dst, const Buffer& moments, const Buffer& src, const Buffer& mask,
                 const NormaliseParams& params);
  // tensor (4 ch: d11 d12 d22, unused) and preconditioned steps (4 ch: tau_u tau_v sigma_p1
  // sigma_p2) from the image and mask (1 ch each). params.sigma >= 0, ceil(3 sigma) <=
  // kMaxTensorRadius.
  void structureTensor(const Buffer& tensor, const Buffer& steps, const Buffer& image, const Buffer& mask,
                       const TensorParams& params);
  // tangent g = normalize(T(x + w)) (2 ch) and the data term at x + w. With a confidence
  // buffer (1 ch; id -1 = none), iz and iu are scaled by max(confidence, weightFloor):
  // lambda c |rho| = lambda |c rho|, so unreliable pixels pull less on the solution and
  // the primal-dual kernel stays unchanged. data 1 ch each, i0, i1, u, mask 1 ch,
  // trajectory and w 2 ch.
  void warpDerivatives(const DataTermBuffers& data, const Buffer& tangent, const Buffer& i0, const Buffer& i1,
                       const Buffer& trajectory, const Buffer& w, const Buffer& u, const Buffer& mask,
                       const Buffer& confidence, float weightFloor);
  // schedule.size() primal-dual iterations (Jacobi-parallel over pixels). The channels of
  // PrimalDualBuffers and DataTermBuffers; tensor, steps 4 ch, mask 1 ch.
  void primalDual(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor, const Buffer& steps,
                  const Buffer& mask, const PrimalDualParams& params);
  // dst = 3x3 median of src over masked neighbours (1 ch each, dst != src).
  void median(const Buffer& dst, const Buffer& src, const Buffer& mask);
  // du = clamp(u - u0, +-duMax); u = u0 + du; w += du * tangent (masked pixels only).
  // u, u0, mask 1 ch, w, tangent 2 ch; duMax >= 0.
  void accumulate(const Buffer& u, const Buffer& w, const Buffer& u0, const Buffer& tangent, const Buffer& mask,
                  float duMax);

  // --- coarse kernels: fixed sequences of the kernels above, which a backend may fuse ---
  // The pipeline calls these where it needs the sequence; the default implementations
  // call the kernels above in the order written, and an override must give the same
  // results as that order. Each checks the contracts of the whole sequence first.
  // A warp's iterations, starting from the over-relaxed primals equal to the primals:
  //   copy(pd.uBar, pd.u); copy(pd.vBar, pd.v); primalDual(pd, data, tensor, steps, mask, params).
  void warpIterations(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                      const Buffer& steps, const Buffer& mask, const PrimalDualParams& params);
  // The end of a warp and, with nextWarp, the start of the next (medianScratch id -1: no median):
  //   median(medianScratch, warp.u, warp.mask); copy(warp.u, medianScratch);   [with a median]
  //   accumulate(warp.u, warp.w, warp.data.u0, warp.tangent, warp.mask, duMax);
  //   warpDerivatives(warp.data, warp.tangent, warp.i0, warp.i1, warp.trajectory, warp.w, warp.u,
  //                   warp.mask, warp.confidence, warp.weightFloor);          [with nextWarp]
  void warpTail(const WarpBuffers& warp, const Buffer& medianScratch, float duMax, bool nextWarp);

  // --- plane-sweep initialisation (one file / shader per kernel family: plane_sweep) ---
  // Every sweep kernel: 2 <= p.planes <= kMaxSweepPlanes, p.radius >= 0; volume, costs and
  // aggregated have p.planes channels, best and other 2, images and mask 1.
  // volume: `image` bilinearly sampled at x_k for every hypothesis k where the
  // reference pixel is in `mask` and x_k is a valid projection inside the image; -1 elsewhere.
  void sweepWarp(const Buffer& volume, const Buffer& image, const Buffer& mask, const SweepParams& p);
  // costs: for each masked pixel and hypothesis, 1 - ZNCC between the
  // reference window and the volume window (masked, non-negative samples only; at least
  // half the window); 2 where fewer scored and outside the mask.
  void sweepCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& mask,
                 const SweepParams& p);
  // aggregated: semi-global aggregation (Hirschmueller 2008) of the costs along
  // the scanline directions r = +x, -x, +y, -y, in that order, summed: at a masked pixel
  // x, with C = min(cost, 1), L_r(x, k) = C(x, k) where x - r is not masked (or outside),
  // else C(x, k) + min(L_r(x - r, k), L_r(x - r, k -+ 1) + p1, m + p2) - m with m the
  // minimum of L_r(x - r, .); aggregated = ((L_+x + L_-x) + L_+y) + L_-y. 0 outside the mask.
  void sweepAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& mask, const SweepParams& p);
  // best: for each masked pixel, the hypothesis minimising `aggregated` among those
  // whose cost scored (< 2), the first on ties, refined by a parabola through
  // aggregated / 4 at its neighbours (offset clamped to +-0.5 planes; none where a
  // neighbour did not score): (q, its cost). (-1, 2) where nothing scored.
  void sweepSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                   const SweepParams& p);
  // From the reference sweep `best` (made with p.t) and the other view's `other` (made
  // with -p.t): confidence = exp(-(e / tol)^2), e the distance from x to its round trip
  // through `other` (nearest pixel at x_q), 0 where the reference has no hypothesis, the
  // round trip fails or mask is 0. u and w (in/out, the coarse-to-fine estimate) become
  // w = x_q - x, u = |w| where confidence >= acceptConfidence. Then (a second pass over
  // those results) an inconsistent pixel whose round trip could be made is checked for
  // occlusion: one-pixel steps along d = J t / |J t| (J the projection's Jacobian at the
  // ray), positions rounded to the nearest pixel, up to p.planes steps each way and
  // stopping at the mask, find the first pixel with confidence >= acceptConfidence
  // behind (-d) and ahead (+d); if both exist and q(behind) > q(ahead), the pixel takes
  // q(ahead): w = x_q(ahead) - x. Every other pixel keeps u and w. u, confidence 1 ch, w 2 ch.
  void sweepInitialise(const Buffer& u, const Buffer& w, const Buffer& confidence, const Buffer& best,
                       const Buffer& other, const Buffer& mask, const SweepParams& p, const ConsistencyParams& c);

  // --- the band sweep (same family): a full sweep one level coarser proposes, the level's ---
  // sweep scores only p.band hypotheses a pixel around the proposal (Params::initBand).
  // `first` (1 ch) says which: channel k of volume, costs and aggregated is hypothesis
  // first + k. Every band kernel: the sweep kernels' contract, and 2 <= p.band <=
  // min(p.planes, kMaxSweepBand); volume, costs and aggregated have p.band channels.
  // first: at a masked pixel x, the coarse pixel c = min(cw - 1, int((x + 0.5) s)) (and the
  // same in y; s = coarseScale, coarse / fine; float arithmetic); a coarse pixel's plane is
  // n = floor(q (planes - 1) / qMax + 0.5) (double) of its hypothesis q = coarseBest (2 ch,
  // as sweepSelect writes it; made with the same qMax), none where q < 0. With lo, hi the
  // lowest and highest plane among the 3x3 coarse pixels around c (inside the coarse image,
  // with a plane): centre = (lo + hi + 1) / 2 if hi - lo + 2 kBandMargin <= band, else c's
  // plane; first = clamp(centre - band / 2, 0, planes - band); -1 where x is not masked or
  // c has no plane. volume: channel k is sweepWarp's value at hypothesis first + k; -1
  // where first is -1.
  void sweepBandWarp(const Buffer& volume, const Buffer& first, const Buffer& image, const Buffer& coarseBest,
                     const Buffer& mask, const SweepParams& p, float coarseScale);
  // costs: sweepCost's 1 - ZNCC at each pixel's hypotheses, in the same summation order,
  // where a window sample at pixel y for hypothesis h = first(x) + k is volume(y, h -
  // first(y)) when first(y) >= 0 and that channel exists, and missing otherwise; 2 where
  // first(x) is -1 or outside the mask.
  void sweepBandCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& first,
                     const Buffer& mask, const SweepParams& p);
  // aggregated: sweepAggregate over bands: a pixel with first -1 ends the path as an unmasked
  // one does; at hypothesis h = first(x) + k the previous pixel's terms are L_r(x - r, h) and
  // L_r(x - r, h -+ 1) where its band holds them (omitted otherwise), m + p2 always, in that
  // order of minima; m is the minimum over the previous pixel's band.
  void sweepBandAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& first, const Buffer& mask,
                          const SweepParams& p);
  // best: sweepSelect within each pixel's band (hypothesis first + k + offset), except that a
  // winner on an edge of the band that is not an end of the full range gives (-1, 2): the
  // minimum lies at or beyond the band, so the coarse proposal missed it.
  void sweepBandSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& first,
                       const Buffer& mask, const SweepParams& p);

  // --- sequences (one file / shader per kernel: carry_estimate, temporal_filter) ---
  // A state is 2 ch: q, the inverse radial depth (1/m, >= 0; 0 at infinity) from the view's
  // centre, and v, its variance (px^2); q < 0 is no estimate. motion is a buffer of
  // kMotionFloats (1 ch, 12x1; uploaded each frame, so a recorded frame replays with the
  // frame's own motion): R row-major, then t; a point X of src's view is R X + t in dst's,
  // plus p.extraT.
  // dst (2 ch, p.dstCam's grid): src (2 ch, p.srcCam's grid) seen from the new view, by a
  // backward fixed point: T = t + extraT, ray = dstCam.unproject(x); the first q is 1 /
  // guess(x) (guess 1 ch on dst's grid, radial depth: +inf gives 0; NaN or <= 0 gives
  // none) or, without a guess (id -1), src's q at the nearest src pixel to
  // srcCam.project(ray); then p.iterations times: s = src at the nearest pixel to
  // srcCam.project(R^T (ray - q T)), ray_s = srcCam.unproject(that pixel), q = q_s / |R ray_s
  // + q_s T|, v = v_s. The nearest pixel is floor(c + 0.5 - kCarryTie) per coordinate, in
  // double: a coarser grid's pixel centres fall exactly halfway between a finer grid's, and
  // rounding must not pick a side differently on each backend. (-1, 0) where x is
  // not masked or not unprojectable, or a step finds no estimate (the pixel outside src's
  // image, an invalid projection or unprojection, q_s < 0). mask 1 ch on dst's grid.
  void carryEstimate(const Buffer& dst, const Buffer& src, const Buffer& guess, const Buffer& motion,
                     const Buffer& mask, const CarryParams& p);
  // The measurement is this frame's radial depth (1 ch): at a masked pixel where it is not
  // NaN, q_m = 1 / radial (0 at +inf), g = |J t'| (J the projection's Jacobian at x's unit
  // ray: px per unit of q), R = (p.sigmaPx / max(confidence, p.minConfidence))^2 (confidence
  // 1 ch, id -1: 1 everywhere), and from the prior (2 ch, carryEstimate's) P = v_p +
  // p.processPx^2. Where the prior has no estimate or (g (q_m - q_p))^2 > p.gate^2 (P + R),
  // state = (q_m, R) and u, w are kept (the new value at once: a moving object leaves no
  // trail). Else K = max(P / (P + R), 1 - p.strength), q = q_p + K (q_m - q_p), state = (q,
  // (1 - K)^2 P + K^2 R), and, with p.strength > 0, where cam.project(ray + q t') is valid: w =
  // that projection - x, u = |w|, radial = 1 / q (+inf at q = 0) and points = ray / q (NaN at
  // q = 0), as triangulate() would give from the new w (at strength 0 q is the measurement's
  // and nothing else changes). Elsewhere state = (-1, 0) and the rest is kept. state, prior
  // 2 ch; u, radial, mask 1 ch; w 2 ch; points 3 ch; state is not prior.
  void temporalFilter(const Buffer& state, const Buffer& u, const Buffer& w, const Buffer& prior, const Buffer& radial,
                      const Buffer& points, const Buffer& confidence, const Buffer& mask, const TemporalParams& p);

  // --- plain regions (Params::plainFill: backend_cpu/plain_fill.cpp, shaders plain_support, fill_planes) ---
  // A level pixel (x, y) of a coarse grid covers the full-resolution pixels (X, Y) with
  // floor((2X + 1) W / (2 W0)) = x and floor((2Y + 1) H / (2 H0)) = y, W x H the coarse
  // grid's size and W0 x H0 the full one's: integer arithmetic, the same pixels everywhere.
  // support (6 ch, coarse): the most confident masked pixel of the block each level pixel
  // covers (the first in row order among equals; NaN confidence is none): X, Y, w(X, Y) and
  // its confidence; where the block has none, 0, 0, 0, 0, -1. Channel 5: the variance of
  // levelImage over the level pixel's 5 x 5 window's pixels masked in levelMask (float, the
  // mean first, rows then columns in order), or -1 where the pixel is not masked or fewer
  // than 13 of the 25 are. confidence, mask 1 ch and w 2 ch on one grid; levelImage and
  // levelMask 1 ch on support's.
  void plainSupport(const Buffer& support, const Buffer& confidence, const Buffer& w, const Buffer& mask,
                    const Buffer& levelImage, const Buffer& levelMask);
  // At each masked full-resolution pixel x whose coarse pixel (as above) has a label l >= 0
  // (labels 2 ch, coarse: l and the plane's confidence there; planes 1 ch, at least
  // 3 (l + 1) values): with a = planes[3l .. 3l + 2] and ray the unit ray of x, q = a . ray;
  // where q >= 0 and ray + q t' projects, w(x) = pi(ray + q t') - x, u(x) = |w(x)| (the
  // sweep's setWarp) and planeConfidence(x) the label's confidence. Elsewhere u and w are
  // unchanged and planeConfidence is 0. u, planeConfidence, mask 1 ch and w 2 ch on cam0's
  // grid.
  void fillPlanes(const Buffer& u, const Buffer& w, const Buffer& planeConfidence, const Buffer& labels,
                  const Buffer& planes, const Buffer& mask, const CameraParams& cam0, const double tPrime[3]);

  // --- the result's confidence (one file / shader per kernel: result_confidence, round_trip) ---
  // error (1 ch): the left-right round trip of x through the other direction's solve. a = x
  // + w(x) (calibrated image 1), y = a + calibration(a) (image 1's pixel), b = y + reverseW(y)
  // (the other solve's calibrated image 0), z = b + reverseCalibration(b); error = |z - x|.
  // Samples are sampleBilinear's (clamped to the edge); NaN where x is not masked, where a,
  // y or b falls outside its image or y's nearest pixel floor(y + 0.5) is not in
  // reverseMask, or where a sample is not finite. w, calibration 2 ch on mask's grid;
  // reverseW, reverseCalibration 2 ch and reverseMask 1 ch on image 1's grid.
  void roundTrip(const Buffer& error, const Buffer& w, const Buffer& calibration, const Buffer& reverseW,
                 const Buffer& reverseCalibration, const Buffer& reverseMask, const Buffer& mask);
  // confidence (1 ch, [0, 1]) of the final estimate, the product of four terms at a masked
  // pixel x whose radial is not NaN (0 elsewhere):
  // - structure: with g = trajectory(x) (unit) and S = sum over the window's pixels y that
  //   are masked with their four neighbours of (g . grad image(y))^2 (central differences),
  //   S sigmaPx^2 / (S sigmaPx^2 + 2 noise^2): 1/2 where the Cramer-Rao deviation of a shift
  //   along the curve, noise sqrt(2 / S), is sigmaPx; or planeConfidence(x) where that is
  //   larger (fillPlanes': the same form for the plane's deviation; id -1: none);
  // - photometric: exp(-(r / residualScale)^2), r the mean over the window's masked pixels y
  //   with a finite w(y) of |n1(y + w(y)) - n0(y)| (bilinear; 0 terms: r = +inf);
  // - sweep: sweepConfidence(x) clamped to [0, 1], or planeConfidence(x) where larger (the
  //   sweep's check says as little about a plain region as its image does; id -1: 1);
  // - round trip: exp(-(e / roundTripPx)^2) for roundTrip's error e (id -1: 1).
  // Then, in order: a pixel whose e is NaN or above roundTripMaxPx (> 0), whose confidence is
  // below invalidBelow, or whose structure term is below 1 / (1 + (maxDeviationPx /
  // sigmaPx)^2) (maxDeviationPx > 0: the deviation beyond maxDeviationPx) is invalid: radial and points NaN, confidence
  // 0; else where |w(x)| < infinityPx, or (infinityBoundPx > 0) |w(x)| < 2 d and |w(x)| + 2 d
  // <= infinityBoundPx for d = sigmaPx sqrt(1/s - 1) of the structure term s above, radial is
  // +inf and points NaN. image, n0, n1, radial, mask 1 ch; w, trajectory 2
  // ch; points 3 ch; one grid.
  void resultConfidence(const Buffer& confidence, const Buffer& radial, const Buffer& points, const Buffer& image,
                        const Buffer& n0, const Buffer& n1, const Buffer& w, const Buffer& trajectory,
                        const Buffer& sweepConfidence, const Buffer& roundTripError, const Buffer& planeConfidence,
                        const Buffer& mask, const ConfidenceParams& p);

  // --- the result as the user sees it (finish_result) ---
  // A pixel is solved where radial is not NaN and disparity and warp are finite: a solver
  // failure, or a warp that left the camera model's valid region, is reported unsolved
  // rather than passed on as depth. Where solved: valid 1, z = points.z, or +inf where radial
  // is +inf (a point at infinity has infinite z, also beyond 90 degrees). Elsewhere: valid 0
  // and radial, z, points, disparity, warp and confidence the quiet NaN 0x7fc00000 (one NaN,
  // so outputs compare bit for bit across backends). radial, points, disparity, warp and
  // confidence in place; valid and z written. valid, z, radial, disparity, confidence 1 ch;
  // warp 2 ch; points 3 ch; one grid. Every output, whichever the caller reads: Stereo and
  // DeviceStereo then return the same pixels, and the valid mask never depends on which
  // outputs were asked for.
  void finishResult(const Buffer& valid, const Buffer& z, const Buffer& radial, const Buffer& points,
                    const Buffer& disparity, const Buffer& warp, const Buffer& confidence);

  // radial depth (1 ch) and 3-D points (3 ch, camera-0 frame) from the warp w (2 ch) where
  // mask is set: NaN elsewhere, radial +inf (points NaN) where the rays do not converge.
  // radial is NaN outside the mask: Stereo derives the valid mask from radial instead of
  // downloading the mask. cam0's width and height are the buffers'.
  void triangulate(const Buffer& radial, const Buffer& points, const Buffer& w, const Buffer& mask,
                   const CameraParams& cam0, const double tPrime[3]);

  // --- a rig's panorama (one file / shader per kernel: panorama) ---
  // All arithmetic in float. place (5 ch), radial (1 ch), rays (3 ch): one camera's grid.
  // At pixel x with radial r (NaN: no estimate; +inf: at infinity) and ray d (the camera's
  // unit ray turned into the panorama's frame; NaN in any component: none): where r is NaN
  // or d is not finite, place = NaN x 5. Else the point P = r d + centre (d where r is +inf:
  // a point at infinity is its direction), its column lon = atan2(P.x, P.z), row lat =
  // atan2(-P.y, sqrt(P.x^2 + P.z^2)), place = ((lon + pi) / (2 pi) W - 0.5, (pi/2 - lat) / pi
  // H - 0.5, hx, hy, range) with W = p.width, H = W / 2, range = |P| (+inf where r is +inf).
  // The footprint: a = b = (0, 0); for the neighbours (x+1, y), (x, y+1), (x-1, y), (x, y-1)
  // in that order, inside the grid, with a radial rn that is not NaN, a finite ray, and rn
  // on x's surface (|1/rn - 1/r| <= kPanoramaAgreement max(1/rn, 1/r) + p.parallaxSlack): step = (column, row)
  // of the neighbour minus x's (placed the same way); where |step.x| > W/2, step.x =
  // remainder(step.x, W) (across the seam); a (row neighbours) or b (column neighbours) =
  // max(itself, |step|) per axis. With s = a + b and latitude l = pi/2 - pi (row + 0.5) / H:
  // hx = clamp(s.x / 2, 0.5, kPanoramaMaxSplat / max(cos l, 2 kPanoramaMaxSplat / W)) and
  // hy = clamp(s.y / 2, 0.5, kPanoramaMaxSplat).
  void panoramaPlace(const Buffer& place, const Buffer& radial, const Buffer& rays, const PanoramaParams& p);
  // One pass of one camera's pixels into accum (6 ch, W x W/2): best confidence, nearest
  // inverse range, sum of w / range, sum of w, sum of w grey, sum of w where grey is finite.
  // A pixel splats where its place's column is not NaN and (p.minConfidence <= 0 or its
  // confidence >= p.minConfidence); c is its confidence (0 where not finite), w = max(c,
  // 1e-6) (1e-6 where not finite), g its grey (NaN: none; grey id -1: none). It covers the
  // panorama pixels of columns ceil(col - hx) .. floor(col + hx), wrapped modulo W, and rows
  // max(0, ceil(row - hy)) .. min(H - 1, floor(row + hy)). At each, by p.pass:
  // - kPanoramaBest: best = max(best, c);
  // - kPanoramaNearest: where c >= 0.5 best, nearest = max(nearest, 1 / range);
  // - kPanoramaSums: where c >= 0.5 best and |1/range - nearest| <= kPanoramaAgreement
  //   max(1/range, nearest) + p.parallaxSlack: the sums += w (1/range), w, and where g is finite w g, w.
  // Every camera's best pass runs before any nearest pass, and those before the sums. The
  // order of the sums is the backend's (GPUs: atomics), so they agree to rounding.
  // confidence, grey 1 ch on place's grid.
  void panoramaSplat(const Buffer& accum, const Buffer& place, const Buffer& confidence, const Buffer& grey,
                     const PanoramaParams& p);
  // range, grey, confidence (1 ch, accum's grid): where the sum of w is not > 0, NaN x 3;
  // else range = sum w / sum (w / range) (+inf where that sum is 0), confidence = best, grey
  // = sum w g / its sum of w (NaN where that is not > 0). accum is then all 0 again, the
  // state panoramaSplat starts from (fill it with 0 once after create()).
  void panoramaResolve(const Buffer& range, const Buffer& grey, const Buffer& confidence, const Buffer& accum);

  // Waits until all enqueued work is done.
  virtual void synchronize() {}

  // --- frame replay ---
  // The pipeline issues the same kernel sequence every frame (uploads and downloads stay
  // outside it). It brackets that sequence with beginFrame()/endFrame(); a backend that
  // can record it (a CUDA graph, a Vulkan command buffer) returns true from
  // canReplayFrame() afterwards, and the pipeline then calls replayFrame() instead of
  // issuing the kernels again. Never used while stage timing is on.
  // A sequence issues up to kFrameSlots different frames (cold or warm, with or without the
  // temporal filter): each has its slot, recorded and replayed on its own.
  virtual void beginFrame(int slot) { (void)slot; }
  virtual void endFrame() {}
  virtual bool canReplayFrame(int slot) const {
    (void)slot;
    return false;
  }
  virtual void replayFrame(int slot) { (void)slot; }

  // --- stage timing ---
  // beginStage() ends the current stage and starts the named one; takeStageTimes() ends
  // the last and returns the time per stage name (summed, first-seen order) since the
  // previous call. The default synchronises and reads the host clock; GPU backends may
  // use device timestamps instead.
  virtual void beginStage(const std::string& name);
  virtual std::vector<StageTime> takeStageTimes();

 protected:
  // What each backend implements: the public method of the same name without "do", its
  // arguments already checked.
  virtual Buffer doCreate(int width, int height, int channels) = 0;
  virtual void doUpload(const Buffer& dst, const float* host, bool* finite) = 0;  // finite: see copyFloats
  virtual void doUploadBytes(const Buffer& dst, const uint8_t* host) = 0;
  virtual void doDownload(const Buffer& src, float* host) = 0;
  // By default one doDownload each; a GPU backend overrides it with one wait.
  virtual void doDownloadAll(const std::vector<Download>& downloads);
  virtual void doFill(const Buffer& dst, float value) = 0;
  virtual void doCopy(const Buffer& dst, const Buffer& src) = 0;
  virtual void doFields(const Buffer& mask, const Buffer& calibration, const Buffer& trajectory,
                        const FieldsParams& params) = 0;
  virtual void doWarp(const Buffer& dst, const Buffer& src, const Buffer& flow) = 0;
  virtual void doDownsample(const Buffer& dst, const Buffer& src, float scale) = 0;
  virtual void doUpsample(const Buffer& dst, const Buffer& src, float scale, float valueScale) = 0;
  virtual void doUpsampleEstimate(const Buffer& u, const Buffer& w, const Buffer& coarseU, const Buffer& coarseW,
                                  const Buffer& n0, const Buffer& n1, const Buffer& mask,
                                  const EstimateUpsampleParams& p) = 0;
  virtual void doNormalise(const Buffer& dst, const Buffer& moments, const Buffer& src, const Buffer& mask,
                           const NormaliseParams& params) = 0;
  virtual void doStructureTensor(const Buffer& tensor, const Buffer& steps, const Buffer& image, const Buffer& mask,
                                 const TensorParams& params) = 0;
  virtual void doWarpDerivatives(const DataTermBuffers& data, const Buffer& tangent, const Buffer& i0, const Buffer& i1,
                                 const Buffer& trajectory, const Buffer& w, const Buffer& u, const Buffer& mask,
                                 const Buffer& confidence, float weightFloor) = 0;
  virtual void doPrimalDual(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                            const Buffer& steps, const Buffer& mask, const PrimalDualParams& params) = 0;
  virtual void doMedian(const Buffer& dst, const Buffer& src, const Buffer& mask) = 0;
  virtual void doAccumulate(const Buffer& u, const Buffer& w, const Buffer& u0, const Buffer& tangent,
                            const Buffer& mask, float duMax) = 0;
  virtual void doWarpIterations(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                                const Buffer& steps, const Buffer& mask, const PrimalDualParams& params);
  virtual void doWarpTail(const WarpBuffers& warp, const Buffer& medianScratch, float duMax, bool nextWarp);
  virtual void doSweepWarp(const Buffer& volume, const Buffer& image, const Buffer& mask, const SweepParams& p) = 0;
  virtual void doSweepCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& mask,
                           const SweepParams& p) = 0;
  virtual void doSweepAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                                const SweepParams& p) = 0;
  virtual void doSweepSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                             const SweepParams& p) = 0;
  virtual void doSweepInitialise(const Buffer& u, const Buffer& w, const Buffer& confidence, const Buffer& best,
                                 const Buffer& other, const Buffer& mask, const SweepParams& p,
                                 const ConsistencyParams& c) = 0;
  virtual void doSweepBandWarp(const Buffer& volume, const Buffer& first, const Buffer& image, const Buffer& coarseBest,
                               const Buffer& mask, const SweepParams& p, float coarseScale) = 0;
  virtual void doSweepBandCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& first,
                               const Buffer& mask, const SweepParams& p) = 0;
  virtual void doSweepBandAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& first,
                                    const Buffer& mask, const SweepParams& p) = 0;
  virtual void doSweepBandSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& first,
                                 const Buffer& mask, const SweepParams& p) = 0;
  virtual void doFinishResult(const Buffer& valid, const Buffer& z, const Buffer& radial, const Buffer& points,
                              const Buffer& disparity, const Buffer& warp, const Buffer& confidence) = 0;
  virtual void doPlainSupport(const Buffer& support, const Buffer& confidence, const Buffer& w, const Buffer& mask,
                              const Buffer& levelImage, const Buffer& levelMask) = 0;
  virtual void doFillPlanes(const Buffer& u, const Buffer& w, const Buffer& planeConfidence, const Buffer& labels,
                            const Buffer& planes, const Buffer& mask, const CameraParams& cam0,
                            const double tPrime[3]) = 0;
  virtual void doPanoramaPlace(const Buffer& place, const Buffer& radial, const Buffer& rays,
                               const PanoramaParams& p) = 0;
  virtual void doPanoramaSplat(const Buffer& accum, const Buffer& place, const Buffer& confidence, const Buffer& grey,
                               const PanoramaParams& p) = 0;
  virtual void doPanoramaResolve(const Buffer& range, const Buffer& grey, const Buffer& confidence,
                                 const Buffer& accum) = 0;
  virtual void doRoundTrip(const Buffer& error, const Buffer& w, const Buffer& calibration, const Buffer& reverseW,
                           const Buffer& reverseCalibration, const Buffer& reverseMask, const Buffer& mask) = 0;
  virtual void doResultConfidence(const Buffer& confidence, const Buffer& radial, const Buffer& points,
                                  const Buffer& image, const Buffer& n0, const Buffer& n1, const Buffer& w,
                                  const Buffer& trajectory, const Buffer& sweepConfidence, const Buffer& roundTripError,
                                  const Buffer& planeConfidence, const Buffer& mask, const ConfidenceParams& p) = 0;
  virtual void doTriangulate(const Buffer& radial, const Buffer& points, const Buffer& w, const Buffer& mask,
                             const CameraParams& cam0, const double tPrime[3]) = 0;
  virtual void doCarryEstimate(const Buffer& dst, const Buffer& src, const Buffer& guess, const Buffer& motion,
                               const Buffer& mask, const CarryParams& p) = 0;
  virtual void doTemporalFilter(const Buffer& state, const Buffer& u, const Buffer& w, const Buffer& prior,
                                const Buffer& radial, const Buffer& points, const Buffer& confidence,
                                const Buffer& mask, const TemporalParams& p) = 0;

 private:
  friend class BackendContract;  // core/src/backend_contract.cpp: the checks
  std::vector<Buffer> created_;  // by id: the shape each buffer was created with (id -1: none)
  std::vector<StageTime> stages_;
  std::string currentStage_;
  double stageStartMs_ = 0;
};

class Camera;
// The camera in the kernels' form, its constants derived (throws cs::Error for an unknown
// model), and back.
CameraParams toCameraParams(const Camera& camera);
Camera toCamera(const CameraParams& params);

// The registry (stereo/backend_registry.cpp; availableBackends() and backendAvailable() are
// in backends.hpp).
// "auto" picks the first available; an explicit name that is not available throws
// cs::Error naming it and listing the available ones. `why` (optional) receives one line
// saying which backend was taken and why.
std::unique_ptr<Backend> createBackend(const std::string& name, std::string* why = nullptr);

}  // namespace cs

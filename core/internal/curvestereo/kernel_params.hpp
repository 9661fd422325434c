// The kernels' parameters: plain data that the backends take as they are, host C++ (the
// CPU and Vulkan backends, core's checks) and CUDA device code alike. So: no Eigen, no
// standard library types, nothing but fixed-size members; what needs more (the primal-dual
// schedule, buffers) is in backend.hpp, which includes this. Internal, as backend.hpp.
#pragma once

namespace cs {

// The most parameters a camera model has, with room to spare: the fixed size of the
// parameter blocks of every backend (CameraParams, the GLSL Cam).
constexpr int kMaxCameraParams = 12;

// What each model's constructor (camera_models.hpp) precomputes, for the GPU kernels' copies
// of the models, which cannot run the constructors per pixel: Kannala-Brandt a = thetaMax,
// b = radiusMax; unified and extended unified a = w; double sphere a = w2; MEI a = w,
// b = rMax; pinhole-radtan none. In double: a kernel in float rounds them once, as the
// model built in float does.
struct CameraConstants {
  double a = 0, b = 0;
};

// A camera in the flat form kernels take: model as in CameraModel, params as in
// Camera::params ([fx fy cx cy extra...], unused entries zero). toCameraParams (backend.hpp)
// makes one and derives `constants` from model and params; the CPU backend rebuilds the
// model from model and params alone.
struct CameraParams {
  int model = 0;
  int width = 0, height = 0;
  double params[kMaxCameraParams] = {};
  CameraConstants constants;
};

// The relative pose and options of the per-rig fields (docs/design.md "Per rig").
struct FieldsParams {
  CameraParams cam0, cam1;  // cam0 defines the grid
  double R[9];              // row-major, X1 = R X0 + t
  double t[3];
  double maxFovDeg, epipoleDeg;
};

struct TensorParams {
  float beta, eta, wMin;  // w = max(exp(-beta |grad I|^eta), wMin)
  float sigma;            // Gaussian pre-smoothing of the image, px
  float alpha0, alpha1;   // needed for the step sizes
};

// The plane-sweep initialiser (docs/design.md "The plane-sweep initialiser"). Both images are in the
// reference camera's model and orientation (image 1 after the calibration warp), so the
// other view is the reference camera translated: a point X seen from the reference is
// X + t in the other. Hypothesis k (0..planes-1) is the sphere of inverse radial depth
// q_k = qMax k / (planes - 1) around the reference centre; pixel x sees it in the other
// image at x_k = project(unproject(x) + q_k t) (projection ignores the 1/q scale).
struct SweepParams {
  CameraParams cam;  // the level's camera
  double t[3];       // t' (reference = camera 0) or -t' (reference = camera 1)
  double qMax;       // inverse depth of the nearest sphere (1/m)
  int planes;        // >= 2
  int radius;        // ZNCC window: (2 radius + 1)^2 level pixels
  float p1, p2;      // aggregation penalties (cost units): a step to a neighbouring hypothesis, any larger jump
  // Added to both windows' variances in the ZNCC: the image noise's variance, so that a
  // window whose spread is mostly noise (flat walls, sky, a dark rim) correlates weakly
  // with everything instead of strongly with a random hypothesis.
  float flatVariance;
  // Hypotheses per pixel of a band sweep (the sweepBand kernels: 2..min(planes,
  // kMaxSweepBand)); the full sweep's kernels ignore it.
  int band;
};

// Left-right consistency of two sweeps, turned into the initial state and a confidence.
struct ConsistencyParams {
  float tolerancePx;       // reprojection error (level px) at which confidence falls to 1/e
  float acceptConfidence;  // the sweep replaces the coarse-to-fine estimate from this confidence on
  // A winner whose own cost (best's second channel, 1 - ZNCC) is above this matched nothing
  // distinct: its confidence is 0 whatever the round trip (2: never).
  float maxCost;
};

// Local contrast normalisation of an image (docs/design.md "Per frame", the normalised data term): the data term
// compares these instead of grey levels, so a per-camera gain and offset and smooth shading (vignetting) cancel.
// Gaussian taps are computed once, in core (normaliseParams).
constexpr int kMaxNormaliseRadius = 24;
struct NormaliseParams {
  int radius;                               // taps[0 .. 2 radius]
  float taps[2 * kMaxNormaliseRadius + 1];  // normalised Gaussian, taps[radius] at offset 0
  float epsilon;                            // contrast floor (grey levels of [0, 1]): about the sensor's noise
};

// One primal-dual iteration's step sizes (PrimalDualParams::schedule).
struct PrimalDualStep {
  float tauScale;    // multiplies the per-pixel primal steps
  float sigmaScale;  // multiplies the per-pixel dual steps
  float theta;       // over-relaxation
};

// The weights of the TGV-L1 energy (PrimalDualParams, without its schedule).
struct PrimalDualWeights {
  float lambda, alpha0, alpha1;
};

// The most hypotheses a plane sweep may have (SweepParams::planes): the pipeline never asks
// for more, and every backend's sweep kernels take this many (the GPU aggregations hold a
// scanline's planes in registers, at most kMaxSweepPlanes / 32 per lane; Vulkan's fallback
// holds them in shared memory).
constexpr int kMaxSweepPlanes = 512;
// The most hypotheses a band sweep scores per pixel (SweepParams::band): the GPU band
// aggregations give each hypothesis of a scanline's band one lane of a 32-wide group.
constexpr int kMaxSweepBand = 32;
// Hypotheses a band keeps beyond its coarse neighbourhood's winners on each side
// (sweepBandWarp), so that a winner there is not refused as on the band's edge.
constexpr int kBandMargin = 2;
// The structure tensor's Gaussian pre-smoothing: radius ceil(3 sigma) at most this (sigma up
// to 42 px).
constexpr int kMaxTensorRadius = 127;

// How the estimate moves one pyramid level finer (Backend::upsampleEstimate).
constexpr int kMaxUpsampleRadius = 4;
struct EstimateUpsampleParams {
  float scale;  // fine / coarse size ratio (> 1); disparities and displacements grow by it
  float edge;   // px of the fine level: coarse neighbours this far apart straddle a depth edge
  int radius;   // matching window (2 radius + 1)^2, 0..kMaxUpsampleRadius
};

// Carrying a frame's estimate into the next frame's view (Backend::carryEstimate): a
// sequence's warm start and the temporal filter's prior.
constexpr int kMotionFloats = 12;   // the motion buffer: R row-major, then t
constexpr double kCarryTie = 1e-3;  // px: positions this close to halfway go to the lower pixel
struct CarryParams {
  CameraParams srcCam;  // the grid of src (the previous view's camera 0)
  CameraParams dstCam;  // the grid of dst: the same lens, at src's scale or another level's
  double extraT[3];     // added to the motion's t: t' carries into camera 1' (the sweep's other view), 0 into camera 0
  int iterations;       // fixed-point steps, >= 1
};

// The per-pixel temporal filter of a sequence (Backend::temporalFilter): a one-state Kalman
// filter on inverse depth, its variances in px^2 of disparity.
struct TemporalParams {
  CameraParams cam;     // level 0's camera 0
  double tPrime[3];     // t' (triangulate's)
  float strength;       // the prior weighs at most this (gain >= 1 - strength), [0, 1)
  float gate;           // an innovation beyond gate standard deviations resets the pixel, > 0
  float sigmaPx;        // the measurement's standard deviation (px) at confidence 1, > 0
  float processPx;      // how far (px) a static surface's disparity may drift between frames, >= 0
  float minConfidence;  // floor of the confidence in the measurement's deviation, (0, 1]
};

// The final result's confidence and the left-right round trip (Backend::resultConfidence,
// Backend::roundTrip): the evidence a pixel's estimate rests on, and where it is too weak to
// give a depth at all.
constexpr int kMaxConfidenceRadius = 4;
struct ConfidenceParams {
  int radius;             // window (2 radius + 1)^2 of the structure and the residual, 0..kMaxConfidenceRadius
  float noise;            // the image's noise deviation (grey levels of [0, 1]; Params::noiseLevel)
  float sigmaPx;          // disparity deviation (px) at which the structure term is 1/2, > 0
  float residualScale;    // mean |n1(y + w) - n0(y)| at which the photometric term is 1/e, > 0
  float roundTripPx;      // round-trip error (px) at which that term is 1/e, > 0
  float roundTripMaxPx;   // a round trip beyond this (or none) leaves the pixel invalid; <= 0: never
  float infinityPx;       // |w| below this: the point is at infinity (radial +inf, points NaN), >= 0
  float invalidBelow;     // a confidence below this leaves the pixel invalid, [0, 1]
  float maxDeviationPx;   // a structure deviation noise sqrt(2 / S) above this leaves it invalid; 0: never
  float infinityBoundPx;  // |w| within 2 structure deviations of 0, and below this with them: at infinity; 0: never
};

// A rig's equirectangular panorama (Backend::panoramaPlace, panoramaSplat, panoramaResolve;
// core/src/rig_fusion.cpp PanoramaFusion): each camera's pixels placed as footprints in a
// panorama of `width` columns and width / 2 rows, then splatted in three passes.
constexpr float kPanoramaMaxSplat = 3.f;     // a footprint's largest half-size, px of arc
constexpr float kPanoramaAgreement = 0.05f;  // inverse ranges within this share are one surface,
constexpr int kPanoramaPlaceChannels = 5;    // column, row, half-width, half-height, range
constexpr int kPanoramaChannels = 6;         // see Backend::panoramaSplat
enum PanoramaPass : int { kPanoramaBest = 0, kPanoramaNearest = 1, kPanoramaSums = 2 };
struct PanoramaParams {
  int width;            // the panorama's columns, even, 4..32768; its rows width / 2
  float centre[3];      // panoramaPlace: the camera's centre in the panorama's frame (m)
  float minConfidence;  // panoramaSplat: pixels of lower confidence do not splat; <= 0: all do
  int pass;             // panoramaSplat: PanoramaPass
  float parallaxSlack;  // ... or within this of each other (1/m, >= 0): the solves' parallax noise
};

}  // namespace cs

// The CUDA kernels' host-side interface: one launcher per stage (each defined in the .cu
// file named after the stage), taking the kernel parameters of the Backend interface
// (curvestereo/kernel_params.hpp) as they are, plus device buffer views and the few values
// derived from those parameters on the host. Launchers enqueue on the given stream and
// return cudaGetLastError(). Included by host C++ (cuda_backend.cpp) and by the .cu files;
// no Eigen.
#pragma once
#include <cuda_runtime_api.h>
#include <cstdint>

#include "curvestereo/kernel_params.hpp"

namespace cs::cudak {

// A device buffer of `channels` interleaved floats per pixel.
struct Img {
  float* data;
  int width, height, channels;
};

// What the fields take besides FieldsParams: t' = R^T t and its direction, derived on the
// host with Eigen in double, as fieldsAtPixel (core/src/fields.cpp) derives them.
struct FieldsBaseline {
  double tPrime[3];
  double direction[3];  // tPrime normalised
};

// The structure tensor's Gaussian pre-smoothing, derived from TensorParams::sigma on the
// host (cs::gaussianTaps, the oracle's taps): taps[0 .. 2 radius]; radius -1: none (copy).
struct TensorTaps {
  int radius;
  float taps[2 * kMaxTensorRadius + 1];
};

// One primal-dual iteration's steps and the q ascent's factor sigmaScale * 0.5 / alpha0 *
// alpha0: the oracle's per-pixel expression, evaluated once on the host in the same order
// (CudaBackend::iterate).
struct DeviceStep : PrimalDualStep {
  float qAscent;
};

// The primal-dual state: the buffers of the Backend call (set A) and the scratch copies
// (set B) that iterations ping-pong with, so that one launch can run the dual and the
// primal pass of an iteration without racing with neighbouring blocks.
struct PrimalDualDev {
  float* u[2];  // set B's u and v: written by the per-iteration path only (out of place)
  float* v[2];  // 2 ch
  float* uBar[2];
  float* vBar[2];  // 2 ch
  float* p[2];     // 2 ch
  float* q[2];     // 4 ch
  // The over-relaxed primals the first iteration reads: set 0's uBar, vBar, or u, v
  // themselves (uBar = u, vBar = v at the start of every warp, without copying them).
  const float* uBarFirst;
  const float* vBarFirst;  // 2 ch
  const float* u0;
  const float* iu;
  const float* iz;
  const float* tensor;  // 4 ch
  const float* steps;   // 4 ch
  const float* mask;
  int width, height;
  PrimalDualWeights weights;
};

// Queued copies and fills that touch disjoint buffers, run by one launch (src null: fill).
constexpr int kMaxMemOps = 8;
struct MemOp {
  float* dst;
  const float* src;
  size_t count;
  float value;
};
struct MemOps {
  int count;
  MemOp op[kMaxMemOps];
};

cudaError_t launchMemOps(cudaStream_t s, const MemOps& ops);
// A small upload (count <= kMaxInlineFloats) carried by the launch itself: no staging area
// to wait for, so it never blocks the host (the sequence's motion, every frame).
constexpr int kMaxInlineFloats = 16;
struct InlineFloats {
  int count;
  float value[kMaxInlineFloats];
};
cudaError_t launchSetFloats(cudaStream_t s, float* dst, const InlineFloats& values);
// dst[i] = unitFromByte(src[i]) for n bytes (uploadBytes).
cudaError_t launchFloatsFromBytes(cudaStream_t s, float* dst, const uint8_t* src, size_t n);
cudaError_t launchFields(cudaStream_t s, Img mask, Img calibration, Img trajectory, const FieldsParams& p,
                         const FieldsBaseline& baseline);
cudaError_t launchTriangulate(cudaStream_t s, Img radial, Img points, Img w, Img mask, const CameraParams& cam0,
                              const double tPrime[3]);

// Sequences (carry_estimate.cu, temporal_filter.cu; backend.hpp carryEstimate,
// temporalFilter). motion: kMotionFloats floats on the device (R row-major, then t), read
// by the kernel, so that a recorded frame uses each frame's upload.
// guess.data null: none (the first q from src).
cudaError_t launchCarryEstimate(cudaStream_t s, Img dst, Img src, Img guess, const float* motion, Img mask,
                                const CarryParams& p);
// confidence.data null: 1 everywhere.
cudaError_t launchTemporalFilter(cudaStream_t s, Img state, Img u, Img w, Img prior, Img radial, Img points,
                                 Img confidence, Img mask, const TemporalParams& p);
// Plain regions (plain_fill.cu; backend.hpp plainSupport, fillPlanes).
cudaError_t launchPlainSupport(cudaStream_t s, Img support, Img confidence, Img w, Img mask, Img levelImage,
                               Img levelMask);
cudaError_t launchFillPlanes(cudaStream_t s, Img u, Img w, Img planeConfidence, Img labels, Img planes, Img mask,
                             const CameraParams& cam0, const double tPrime[3]);
// A rig's panorama (panorama.cu; backend.hpp panoramaPlace, panoramaSplat, panoramaResolve).
// grey.data null: none.
cudaError_t launchPanoramaPlace(cudaStream_t s, Img place, Img radial, Img rays, const PanoramaParams& p);
cudaError_t launchPanoramaSplat(cudaStream_t s, Img accum, Img place, Img confidence, Img grey,
                                const PanoramaParams& p);
cudaError_t launchPanoramaResolve(cudaStream_t s, Img range, Img grey, Img confidence, Img accum);
// The result's confidence (round_trip.cu, result_confidence.cu; backend.hpp roundTrip,
// resultConfidence).
cudaError_t launchRoundTrip(cudaStream_t s, Img error, Img w, Img calibration, Img reverseW, Img reverseCalibration,
                            Img reverseMask, Img mask);
// sweepConfidence.data, roundTripError.data, planeConfidence.data null: absent. scratch: 4
// floats a pixel (16-byte aligned).
cudaError_t launchResultConfidence(cudaStream_t s, Img confidence, Img radial, Img points, Img image, Img n0, Img n1,
                                   Img w, Img trajectory, Img sweepConfidence, Img roundTripError, Img planeConfidence,
                                   Img mask, const ConfidenceParams& p, float* scratch);
// The result as the user sees it (finish_result.cu; backend.hpp finishResult).
cudaError_t launchFinishResult(cudaStream_t s, Img valid, Img z, Img radial, Img points, Img disparity, Img warp,
                               Img confidence);
cudaError_t launchWarp(cudaStream_t s, Img dst, Img src, Img flow);
cudaError_t launchDownsample(cudaStream_t s, Img dst, Img src, float scale);
cudaError_t launchUpsample(cudaStream_t s, Img dst, Img src, float scale, float valueScale);
cudaError_t launchUpsampleEstimate(cudaStream_t s, Img u, Img w, Img coarseU, Img coarseW, Img n0, Img n1, Img mask,
                                   const EstimateUpsampleParams& p);
// moments: 3 ch scratch (the horizontal pass's sums of weight, weight src, weight src^2).
cudaError_t launchNormalise(cudaStream_t s, Img dst, Img moments, Img src, Img mask, const NormaliseParams& p);
// tmpRows, tmpSmooth: scratch of image.width * image.height floats each.
cudaError_t launchStructureTensor(cudaStream_t s, Img tensor, Img steps, Img image, Img mask, const TensorParams& p,
                                  const TensorTaps& taps, float* tmpRows, float* tmpSmooth);
// What warpDerivatives writes besides u0 (the data term's slope and offset, and the
// tangent of the epipolar curve at x + w), and what it reads besides w and u.
struct DataTermOut {
  Img iu, iz, tangent;
};
struct DataTermIn {
  Img i0, i1, trajectory, mask;
  Img confidence;  // data null: every pixel weighs 1
  float weightFloor;
};
cudaError_t launchWarpDerivatives(cudaStream_t s, Img u0, const DataTermOut& out, const DataTermIn& in, Img w,
                                  Img u);  // confidence.data may be null
// Blocks of the tiled primal-dual kernel the device holds at once.
int primalDualTiledResidentBlocks(int device);
// `count` iterations, the first reading set 0 (uBar, vBar from uBarFirst, vBarFirst), in
// launches of five iterations if the level's five-iteration tiles number at most
// residentTiledBlocks, else of two, going from one set to the other each launch.
// geometrySettled: the kernel launched last on the stream wrote none of pd.mask, .tensor,
// .steps (the first launch then loads them before it waits for that kernel to finish).
// endSet: the set that holds the result (0 or 1; the caller swaps the sets' roles rather
// than copying). Pixels outside the mask keep their values.
cudaError_t launchPrimalDual(cudaStream_t s, const PrimalDualDev& pd, const DeviceStep* steps, int count,
                             int residentTiledBlocks, bool geometrySettled, int& endSet);
cudaError_t launchMedian(cudaStream_t s, Img dst, Img src, Img mask);
// With `next` (not null), each pixel then goes on to the next warp's launchWarpDerivatives
// (u0 = the accumulated u; next->mask must be `mask`): a warp's last stage and the next
// warp's first in one pass, since both work on the pixel's own u and w alone.
cudaError_t launchAccumulate(cudaStream_t s, Img u, Img w, Img u0, Img tangent, Img mask, float duMax,
                             const DataTermOut* nextOut = nullptr, const DataTermIn* next = nullptr);
// median = median(u) (launchMedian), then accumulate from it into uOut (launchAccumulate
// with uIn = median, written to uOut instead of u): the warp's two last stages in one pass;
// with `next`, the next warp's derivatives too (as launchAccumulate).
// afterPrimalDual: the kernel launched last on the stream is a launchPrimalDual one (then w,
// u0, the tangent and the mask are loaded before waiting for it to finish).
cudaError_t launchMedianAccumulate(cudaStream_t s, Img uOut, Img median, Img u, Img w, Img u0, Img tangent, Img mask,
                                   float duMax, const DataTermOut* nextOut = nullptr, const DataTermIn* next = nullptr,
                                   bool afterPrimalDual = false);

// volume, costs, aggregated: p.planes channels. best: 2 channels (q, cost). other: the
// reverse sweep's best. launchSweepAggregate: p.planes <= kMaxSweepPlanes (else
// cudaErrorInvalidValue); aggregated and costs must not alias; spare: scratch of three
// times aggregated's size (the directions other than +x, walked at the same time).
cudaError_t launchSweepWarp(cudaStream_t s, Img volume, Img image, Img mask, const SweepParams& p);
cudaError_t launchSweepCost(cudaStream_t s, Img costs, Img reference, Img volume, Img mask, const SweepParams& p);
cudaError_t launchSweepAggregate(cudaStream_t s, Img aggregated, Img spare, Img costs, Img mask, const SweepParams& p);
cudaError_t launchSweepSelect(cudaStream_t s, Img best, Img aggregated, Img costs, Img mask, const SweepParams& p);
cudaError_t launchSweepInitialise(cudaStream_t s, Img u, Img w, Img confidence, Img best, Img other, Img mask,
                                  const SweepParams& p, const ConsistencyParams& c);

// The band sweep (sweep_band.cu): volume, costs and aggregated have p.band channels
// (2 <= p.band <= kMaxSweepBand, else cudaErrorInvalidValue), channel k hypothesis
// first + k; first: 1 ch, written by launchSweepBandWarp from coarseBest (2 ch, the
// coarser level's sweepSelect) and the fine-per-coarse pixel scale. launchSweepBandAggregate:
// aggregated and costs must not alias; spare: scratch of three times aggregated's size.
cudaError_t launchSweepBandWarp(cudaStream_t s, Img volume, Img first, Img image, Img coarseBest, Img mask,
                                const SweepParams& p, float coarseScale);
cudaError_t launchSweepBandCost(cudaStream_t s, Img costs, Img reference, Img volume, Img first, Img mask,
                                const SweepParams& p);
cudaError_t launchSweepBandAggregate(cudaStream_t s, Img aggregated, Img spare, Img costs, Img first, Img mask,
                                     const SweepParams& p);
cudaError_t launchSweepBandSelect(cudaStream_t s, Img best, Img aggregated, Img costs, Img first, Img mask,
                                  const SweepParams& p);

}  // namespace cs::cudak

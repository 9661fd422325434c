// The scalar CPU backend: the readable reference implementation (the oracle) that
// every other backend is tested against. One file per stage (fields.cpp, warp.cpp, resample.cpp,
// upsample_estimate.cpp, normalise.cpp, structure_tensor.cpp, warp_derivatives.cpp, primal_dual.cpp, median.cpp,
// accumulate.cpp, plane_sweep.cpp, triangulate.cpp, carry_estimate.cpp, temporal_filter.cpp,
// round_trip.cpp, result_confidence.cpp, finish_result.cpp, plain_fill.cpp, panorama.cpp).
#pragma once
#include <vector>

#include "cpu_views.hpp"
#include "curvestereo/backend.hpp"

namespace cs::cpu {

// Stage functions (each defined in the file named after its stage).
void fields(const View& mask, const View& calibration, const View& trajectory, const FieldsParams& params);
void triangulate(const View& radial, const View& points, const View& w, const View& mask, const CameraParams& cam0,
                 const double tPrime[3]);
void warp(const View& dst, const View& src, const View& flow);
void downsample(const View& dst, const View& src, float scale);
void upsample(const View& dst, const View& src, float scale, float valueScale);
void upsampleEstimate(const View& u, const View& w, const View& coarseU, const View& coarseW, const View& n0,
                      const View& n1, const View& mask, const EstimateUpsampleParams& p);
void normalise(const View& dst, const View& moments, const View& src, const View& mask, const NormaliseParams& p);
void structureTensor(const View& tensor, const View& steps, const View& image, const View& mask,
                     const TensorParams& params);
void warpDerivatives(const View& u0, const View& iu, const View& iz, const View& tangent, const View& i0,
                     const View& i1, const View& trajectory, const View& w, const View& u, const View& mask,
                     const View* confidence, float weightFloor);
void primalDual(const View& u, const View& uBar, const View& v, const View& vBar, const View& p, const View& q,
                const View& u0, const View& iu, const View& iz, const View& tensor, const View& steps, const View& mask,
                const PrimalDualParams& params);
void median(const View& dst, const View& src, const View& mask);
void accumulate(const View& u, const View& w, const View& u0, const View& tangent, const View& mask, float duMax);
void sweepWarp(const View& volume, const View& image, const View& mask, const SweepParams& p);
void sweepCost(const View& costs, const View& reference, const View& volume, const View& mask, const SweepParams& p);
void sweepAggregate(const View& aggregated, const View& costs, const View& mask, const SweepParams& p);
void sweepSelect(const View& best, const View& aggregated, const View& costs, const View& mask, const SweepParams& p);
void sweepInitialise(const View& u, const View& w, const View& confidence, const View& best, const View& other,
                     const View& mask, const SweepParams& p, const ConsistencyParams& c);
void sweepBandWarp(const View& volume, const View& first, const View& image, const View& coarseBest, const View& mask,
                   const SweepParams& p, float coarseScale);
void sweepBandCost(const View& costs, const View& reference, const View& volume, const View& first, const View& mask,
                   const SweepParams& p);
void sweepBandAggregate(const View& aggregated, const View& costs, const View& first, const View& mask,
                        const SweepParams& p);
void sweepBandSelect(const View& best, const View& aggregated, const View& costs, const View& first, const View& mask,
                     const SweepParams& p);
void carryEstimate(const View& dst, const View& src, const View* guess, const float motion[kMotionFloats],
                   const View& mask, const CarryParams& p);
void temporalFilter(const View& state, const View& u, const View& w, const View& prior, const View& radial,
                    const View& points, const View* confidence, const View& mask, const TemporalParams& p);
void finishResult(const View& valid, const View& z, const View& radial, const View& points, const View& disparity,
                  const View& warp, const View& confidence);
void plainSupport(const View& support, const View& confidence, const View& w, const View& mask, const View& levelImage,
                  const View& levelMask);
void fillPlanes(const View& u, const View& w, const View& planeConfidence, const View& labels, const View& planes,
                const View& mask, const CameraParams& cam0, const double tPrime[3]);
void panoramaPlace(const View& place, const View& radial, const View& rays, const PanoramaParams& p);
void panoramaSplat(const View& accum, const View& place, const View& confidence, const View* grey,
                   const PanoramaParams& p);
void panoramaResolve(const View& range, const View& grey, const View& confidence, const View& accum);
void roundTrip(const View& error, const View& w, const View& calibration, const View& reverseW,
               const View& reverseCalibration, const View& reverseMask, const View& mask);
void resultConfidence(const View& confidence, const View& radial, const View& points, const View& image, const View& n0,
                      const View& n1, const View& w, const View& trajectory, const View* sweepConfidence,
                      const View* roundTripError, const View* planeConfidence, const View& mask,
                      const ConfidenceParams& p);

// Physical memory, or the container's memory limit when lower (0 if unknown): create()
// refuses buffers beyond it with a cs::Error naming the size instead of being OOM-killed.
unsigned long long usableMemoryBytes();

class CpuBackend final : public Backend {
 public:
  std::string name() const override { return "cpu"; }
  std::string device() const override;
  unsigned long long memoryBytes() const override { return usableMemoryBytes(); }

 protected:
  Buffer doCreate(int width, int height, int channels) override;
  void doUpload(const Buffer& dst, const float* host, bool* finite) override;
  void doUploadBytes(const Buffer& dst, const uint8_t* host) override;
  void doDownload(const Buffer& src, float* host) override;
  void doFill(const Buffer& dst, float value) override;
  void doCopy(const Buffer& dst, const Buffer& src) override;

  void doFields(const Buffer& mask, const Buffer& calibration, const Buffer& trajectory,
                const FieldsParams& params) override;
  void doWarp(const Buffer& dst, const Buffer& src, const Buffer& flow) override;
  void doDownsample(const Buffer& dst, const Buffer& src, float scale) override;
  void doUpsample(const Buffer& dst, const Buffer& src, float scale, float valueScale) override;
  void doUpsampleEstimate(const Buffer& u, const Buffer& w, const Buffer& coarseU, const Buffer& coarseW,
                          const Buffer& n0, const Buffer& n1, const Buffer& mask,
                          const EstimateUpsampleParams& p) override;
  void doNormalise(const Buffer& dst, const Buffer& moments, const Buffer& src, const Buffer& mask,
                   const NormaliseParams& params) override;
  void doStructureTensor(const Buffer& tensor, const Buffer& steps, const Buffer& image, const Buffer& mask,
                         const TensorParams& params) override;
  void doWarpDerivatives(const DataTermBuffers& data, const Buffer& tangent, const Buffer& i0, const Buffer& i1,
                         const Buffer& trajectory, const Buffer& w, const Buffer& u, const Buffer& mask,
                         const Buffer& confidence, float weightFloor) override;
  void doPrimalDual(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor, const Buffer& steps,
                    const Buffer& mask, const PrimalDualParams& params) override;
  void doMedian(const Buffer& dst, const Buffer& src, const Buffer& mask) override;
  void doAccumulate(const Buffer& u, const Buffer& w, const Buffer& u0, const Buffer& tangent, const Buffer& mask,
                    float duMax) override;
  void doSweepWarp(const Buffer& volume, const Buffer& image, const Buffer& mask, const SweepParams& p) override;
  void doSweepCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& mask,
                   const SweepParams& p) override;
  void doSweepAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                        const SweepParams& p) override;
  void doSweepSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                     const SweepParams& p) override;
  void doSweepBandWarp(const Buffer& volume, const Buffer& first, const Buffer& image, const Buffer& coarseBest,
                       const Buffer& mask, const SweepParams& p, float coarseScale) override;
  void doSweepBandCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& first,
                       const Buffer& mask, const SweepParams& p) override;
  void doSweepBandAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& first, const Buffer& mask,
                            const SweepParams& p) override;
  void doSweepBandSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& first,
                         const Buffer& mask, const SweepParams& p) override;
  void doSweepInitialise(const Buffer& u, const Buffer& w, const Buffer& confidence, const Buffer& best,
                         const Buffer& other, const Buffer& mask, const SweepParams& p,
                         const ConsistencyParams& c) override;
  void doTriangulate(const Buffer& radial, const Buffer& points, const Buffer& w, const Buffer& mask,
                     const CameraParams& cam0, const double tPrime[3]) override;
  void doCarryEstimate(const Buffer& dst, const Buffer& src, const Buffer& guess, const Buffer& motion,
                       const Buffer& mask, const CarryParams& p) override;
  void doTemporalFilter(const Buffer& state, const Buffer& u, const Buffer& w, const Buffer& prior,
                        const Buffer& radial, const Buffer& points, const Buffer& confidence, const Buffer& mask,
                        const TemporalParams& p) override;
  void doFinishResult(const Buffer& valid, const Buffer& z, const Buffer& radial, const Buffer& points,
                      const Buffer& disparity, const Buffer& warp, const Buffer& confidence) override;
  void doPlainSupport(const Buffer& support, const Buffer& confidence, const Buffer& w, const Buffer& mask,
                      const Buffer& levelImage, const Buffer& levelMask) override;
  void doFillPlanes(const Buffer& u, const Buffer& w, const Buffer& planeConfidence, const Buffer& labels,
                    const Buffer& planes, const Buffer& mask, const CameraParams& cam0,
                    const double tPrime[3]) override;
  void doPanoramaPlace(const Buffer& place, const Buffer& radial, const Buffer& rays, const PanoramaParams& p) override;
  void doPanoramaSplat(const Buffer& accum, const Buffer& place, const Buffer& confidence, const Buffer& grey,
                       const PanoramaParams& p) override;
  void doPanoramaResolve(const Buffer& range, const Buffer& grey, const Buffer& confidence,
                         const Buffer& accum) override;
  void doRoundTrip(const Buffer& error, const Buffer& w, const Buffer& calibration, const Buffer& reverseW,
                   const Buffer& reverseCalibration, const Buffer& reverseMask, const Buffer& mask) override;
  void doResultConfidence(const Buffer& confidence, const Buffer& radial, const Buffer& points, const Buffer& image,
                          const Buffer& n0, const Buffer& n1, const Buffer& w, const Buffer& trajectory,
                          const Buffer& sweepConfidence, const Buffer& roundTripError, const Buffer& planeConfidence,
                          const Buffer& mask, const ConfidenceParams& p) override;

 private:
  // The view of a buffer (Backend has checked it: created here, used no larger).
  View view(const Buffer& b) { return View{storage_[size_t(b.id)].data(), b.width, b.height, b.channels}; }

  std::vector<std::vector<float>> storage_;
  unsigned long long allocatedBytes_ = 0;
};

}  // namespace cs::cpu

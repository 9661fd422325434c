#include "cpu_backend.hpp"

#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <new>

#include "curvestereo/image.hpp"
#include "curvestereo/parallel.hpp"

namespace cs::cpu {

unsigned long long usableMemoryBytes() {
  unsigned long long bytes = 0;
  const long pages = sysconf(_SC_PHYS_PAGES), pageSize = sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && pageSize > 0) bytes = (unsigned long long)pages * (unsigned long long)pageSize;
  // A container's memory limit (cgroup v2, then v1) is what the kernel enforces.
  for (const char* path : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    std::ifstream file(path);
    unsigned long long limit = 0;
    if (file >> limit && limit > 0 && (bytes == 0 || limit < bytes)) bytes = limit;
  }
  return bytes;
}

void parallelRows(int height, const std::function<void(int)>& body) { detail::parallelFor(height, body, 32); }

std::string CpuBackend::device() const {
  return "CPU, " + std::to_string(detail::parallelWorkers()) + " threads (scalar reference)";
}

Buffer CpuBackend::doCreate(int width, int height, int channels) {
  Buffer b{int(storage_.size()), width, height, channels};
  const unsigned long long bytes = (unsigned long long)b.count() * sizeof(float);
  // Refuse what the machine cannot hold before touching it: with overcommit, allocating
  // succeeds and zero-filling it gets the process killed instead of a bad_alloc.
  const std::string what = "cpu backend: out of memory for a " + std::to_string(width) + "x" + std::to_string(height) +
                           "x" + std::to_string(channels) + " float buffer (" + std::to_string(bytes) + " bytes";
  const unsigned long long limit = usableMemoryBytes();
  if (limit && allocatedBytes_ + bytes > limit)
    throw Error(what + "; " + std::to_string(allocatedBytes_) + " bytes already allocated, " + std::to_string(limit) +
                " bytes of memory)");
  try {
    storage_.emplace_back(b.count(), 0.f);
  } catch (const std::bad_alloc&) {
    throw Error(what + "; " + std::to_string(allocatedBytes_) + " bytes already allocated)");
  }
  allocatedBytes_ += bytes;
  return b;
}

void CpuBackend::doUpload(const Buffer& dst, const float* host, bool* finite) {
  copyFloats(view(dst).data, host, dst.count(), finite);
}

void CpuBackend::doUploadBytes(const Buffer& dst, const uint8_t* host) {
  floatsFromBytes(view(dst).data, host, dst.count());
}

void CpuBackend::doDownload(const Buffer& src, float* host) {
  const float* d = view(src).data;
  std::copy(d, d + src.count(), host);
}

void CpuBackend::doFill(const Buffer& dst, float value) { std::fill_n(view(dst).data, dst.count(), value); }

void CpuBackend::doCopy(const Buffer& dst, const Buffer& src) {
  const float* s = view(src).data;
  std::copy(s, s + src.count(), view(dst).data);
}

void CpuBackend::doFields(const Buffer& mask, const Buffer& calibration, const Buffer& trajectory,
                          const FieldsParams& params) {
  cpu::fields(view(mask), view(calibration), view(trajectory), params);
}

void CpuBackend::doTriangulate(const Buffer& radial, const Buffer& points, const Buffer& w, const Buffer& mask,
                               const CameraParams& cam0, const double tPrime[3]) {
  cpu::triangulate(view(radial), view(points), view(w), view(mask), cam0, tPrime);
}

void CpuBackend::doCarryEstimate(const Buffer& dst, const Buffer& src, const Buffer& guess, const Buffer& motion,
                                 const Buffer& mask, const CarryParams& p) {
  const View guessView = guess.id >= 0 ? view(guess) : View{};
  cpu::carryEstimate(view(dst), view(src), guess.id >= 0 ? &guessView : nullptr, view(motion).data, view(mask), p);
}

void CpuBackend::doTemporalFilter(const Buffer& state, const Buffer& u, const Buffer& w, const Buffer& prior,
                                  const Buffer& radial, const Buffer& points, const Buffer& confidence,
                                  const Buffer& mask, const TemporalParams& p) {
  const View confidenceView = confidence.id >= 0 ? view(confidence) : View{};
  cpu::temporalFilter(view(state), view(u), view(w), view(prior), view(radial), view(points),
                      confidence.id >= 0 ? &confidenceView : nullptr, view(mask), p);
}

void CpuBackend::doFinishResult(const Buffer& valid, const Buffer& z, const Buffer& radial, const Buffer& points,
                                const Buffer& disparity, const Buffer& warp, const Buffer& confidence) {
  cpu::finishResult(view(valid), view(z), view(radial), view(points), view(disparity), view(warp), view(confidence));
}

void CpuBackend::doPlainSupport(const Buffer& support, const Buffer& confidence, const Buffer& w, const Buffer& mask,
                                const Buffer& levelImage, const Buffer& levelMask) {
  cpu::plainSupport(view(support), view(confidence), view(w), view(mask), view(levelImage), view(levelMask));
}

void CpuBackend::doFillPlanes(const Buffer& u, const Buffer& w, const Buffer& planeConfidence, const Buffer& labels,
                              const Buffer& planes, const Buffer& mask, const CameraParams& cam0,
                              const double tPrime[3]) {
  cpu::fillPlanes(view(u), view(w), view(planeConfidence), view(labels), view(planes), view(mask), cam0, tPrime);
}

void CpuBackend::doPanoramaPlace(const Buffer& place, const Buffer& radial, const Buffer& rays,
                                 const PanoramaParams& p) {
  cpu::panoramaPlace(view(place), view(radial), view(rays), p);
}

void CpuBackend::doPanoramaSplat(const Buffer& accum, const Buffer& place, const Buffer& confidence, const Buffer& grey,
                                 const PanoramaParams& p) {
  const View greyView = grey.id >= 0 ? view(grey) : View{};
  cpu::panoramaSplat(view(accum), view(place), view(confidence), grey.id >= 0 ? &greyView : nullptr, p);
}

void CpuBackend::doPanoramaResolve(const Buffer& range, const Buffer& grey, const Buffer& confidence,
                                   const Buffer& accum) {
  cpu::panoramaResolve(view(range), view(grey), view(confidence), view(accum));
}

void CpuBackend::doRoundTrip(const Buffer& error, const Buffer& w, const Buffer& calibration, const Buffer& reverseW,
                             const Buffer& reverseCalibration, const Buffer& reverseMask, const Buffer& mask) {
  cpu::roundTrip(view(error), view(w), view(calibration), view(reverseW), view(reverseCalibration), view(reverseMask),
                 view(mask));
}

void CpuBackend::doResultConfidence(const Buffer& confidence, const Buffer& radial, const Buffer& points,
                                    const Buffer& image, const Buffer& n0, const Buffer& n1, const Buffer& w,
                                    const Buffer& trajectory, const Buffer& sweepConfidence,
                                    const Buffer& roundTripError, const Buffer& planeConfidence, const Buffer& mask,
                                    const ConfidenceParams& p) {
  const View sweepView = sweepConfidence.id >= 0 ? view(sweepConfidence) : View{};
  const View tripView = roundTripError.id >= 0 ? view(roundTripError) : View{};
  const View planeView = planeConfidence.id >= 0 ? view(planeConfidence) : View{};
  cpu::resultConfidence(view(confidence), view(radial), view(points), view(image), view(n0), view(n1), view(w),
                        view(trajectory), sweepConfidence.id >= 0 ? &sweepView : nullptr,
                        roundTripError.id >= 0 ? &tripView : nullptr, planeConfidence.id >= 0 ? &planeView : nullptr,
                        view(mask), p);
}

void CpuBackend::doWarp(const Buffer& dst, const Buffer& src, const Buffer& flow) {
  cpu::warp(view(dst), view(src), view(flow));
}

void CpuBackend::doDownsample(const Buffer& dst, const Buffer& src, float scale) {
  cpu::downsample(view(dst), view(src), scale);
}

void CpuBackend::doUpsample(const Buffer& dst, const Buffer& src, float scale, float valueScale) {
  cpu::upsample(view(dst), view(src), scale, valueScale);
}

void CpuBackend::doUpsampleEstimate(const Buffer& u, const Buffer& w, const Buffer& coarseU, const Buffer& coarseW,
                                    const Buffer& n0, const Buffer& n1, const Buffer& mask,
                                    const EstimateUpsampleParams& p) {
  cpu::upsampleEstimate(view(u), view(w), view(coarseU), view(coarseW), view(n0), view(n1), view(mask), p);
}

void CpuBackend::doNormalise(const Buffer& dst, const Buffer& moments, const Buffer& src, const Buffer& mask,
                             const NormaliseParams& params) {
  cpu::normalise(view(dst), view(moments), view(src), view(mask), params);
}

void CpuBackend::doStructureTensor(const Buffer& tensor, const Buffer& steps, const Buffer& image, const Buffer& mask,
                                   const TensorParams& params) {
  cpu::structureTensor(view(tensor), view(steps), view(image), view(mask), params);
}

void CpuBackend::doWarpDerivatives(const DataTermBuffers& data, const Buffer& tangent, const Buffer& i0,
                                   const Buffer& i1, const Buffer& trajectory, const Buffer& w, const Buffer& u,
                                   const Buffer& mask, const Buffer& confidence, float weightFloor) {
  const View c = confidence.id >= 0 ? view(confidence) : View{};
  cpu::warpDerivatives(view(data.u0), view(data.iu), view(data.iz), view(tangent), view(i0), view(i1), view(trajectory),
                       view(w), view(u), view(mask), confidence.id >= 0 ? &c : nullptr, weightFloor);
}

void CpuBackend::doPrimalDual(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                              const Buffer& steps, const Buffer& mask, const PrimalDualParams& params) {
  cpu::primalDual(view(pd.u), view(pd.uBar), view(pd.v), view(pd.vBar), view(pd.p), view(pd.q), view(data.u0),
                  view(data.iu), view(data.iz), view(tensor), view(steps), view(mask), params);
}

void CpuBackend::doMedian(const Buffer& dst, const Buffer& src, const Buffer& mask) {
  cpu::median(view(dst), view(src), view(mask));
}

void CpuBackend::doAccumulate(const Buffer& u, const Buffer& w, const Buffer& u0, const Buffer& tangent,
                              const Buffer& mask, float duMax) {
  cpu::accumulate(view(u), view(w), view(u0), view(tangent), view(mask), duMax);
}

void CpuBackend::doSweepWarp(const Buffer& volume, const Buffer& image, const Buffer& mask, const SweepParams& p) {
  cpu::sweepWarp(view(volume), view(image), view(mask), p);
}

void CpuBackend::doSweepCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& mask,
                             const SweepParams& p) {
  cpu::sweepCost(view(costs), view(reference), view(volume), view(mask), p);
}

void CpuBackend::doSweepAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                                  const SweepParams& p) {
  cpu::sweepAggregate(view(aggregated), view(costs), view(mask), p);
}

void CpuBackend::doSweepSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                               const SweepParams& p) {
  cpu::sweepSelect(view(best), view(aggregated), view(costs), view(mask), p);
}

void CpuBackend::doSweepInitialise(const Buffer& u, const Buffer& w, const Buffer& confidence, const Buffer& best,
                                   const Buffer& other, const Buffer& mask, const SweepParams& p,
                                   const ConsistencyParams& c) {
  cpu::sweepInitialise(view(u), view(w), view(confidence), view(best), view(other), view(mask), p, c);
}

void CpuBackend::doSweepBandWarp(const Buffer& volume, const Buffer& first, const Buffer& image,
                                 const Buffer& coarseBest, const Buffer& mask, const SweepParams& p,
                                 float coarseScale) {
  cpu::sweepBandWarp(view(volume), view(first), view(image), view(coarseBest), view(mask), p, coarseScale);
}

void CpuBackend::doSweepBandCost(const Buffer& costs, const Buffer& reference, const Buffer& volume,
                                 const Buffer& first, const Buffer& mask, const SweepParams& p) {
  cpu::sweepBandCost(view(costs), view(reference), view(volume), view(first), view(mask), p);
}

void CpuBackend::doSweepBandAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& first,
                                      const Buffer& mask, const SweepParams& p) {
  cpu::sweepBandAggregate(view(aggregated), view(costs), view(first), view(mask), p);
}

void CpuBackend::doSweepBandSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs,
                                   const Buffer& first, const Buffer& mask, const SweepParams& p) {
  cpu::sweepBandSelect(view(best), view(aggregated), view(costs), view(first), view(mask), p);
}

}  // namespace cs::cpu

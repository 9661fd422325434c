// The CUDA backend: the kernels of backend.hpp on one CUDA stream, one device buffer per
// Backend buffer (allocated once), pinned host staging for transfers, and each kind of
// frame (Backend::beginFrame's slot) recorded once as a CUDA graph and replayed. This
// header names no CUDA types (core's backend registry includes it): the CUDA handles are
// forward-declared driver structs.
#pragma once
#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "curvestereo/backend.hpp"

namespace cs::cudak {
struct Img;  // kernels.hpp
}

struct CUstream_st;
struct CUevent_st;
struct CUgraph_st;
struct CUgraphExec_st;

namespace cs {

// "" when a CUDA device is usable (device: "" or an index), else the reason.
std::string probeCuda(const std::string& device);
std::unique_ptr<Backend> createCudaBackend(const std::string& device);

namespace cuda {

class CudaBackend final : public Backend {
 public:
  // stream: work is enqueued there (nullptr: the backend creates its own). A user stream
  // must be capturable (not the legacy default stream).
  explicit CudaBackend(int device, CUstream_st* stream = nullptr);
  ~CudaBackend() override;
  CudaBackend(const CudaBackend&) = delete;
  CudaBackend& operator=(const CudaBackend&) = delete;

  std::string name() const override { return "cuda"; }
  std::string device() const override { return description_; }
  unsigned long long memoryBytes() const override { return memoryBytes_; }

  void synchronize() override;

  // Per slot (kFrameSlots, each a kind of frame with its own kernel sequence): the slot's
  // first frame runs directly (it allocates scratch and loads the kernels); its second is
  // captured into the slot's graph, which its later frames replay. Creating buffers drops
  // every slot's graph and starts them afresh; recomputing fields (a new pose) drops the
  // graphs, and each slot's next frame is recorded again. Work queued outside a frame
  // (copy(), fill(), upload(): a sequence's state and motion) is enqueued before it, never
  // recorded. Every frame starts and ends with every buffer in its own memory (see
  // devicePointer()), so the slots' graphs may run in any order.
  void beginFrame(int slot) override;
  void endFrame() override;
  bool canReplayFrame(int slot) const override;
  void replayFrame(int slot) override;

  // Stage times from CUDA events on the stream (no host synchronisation per stage).
  void beginStage(const std::string& name) override;
  std::vector<StageTime> takeStageTimes() override;

  // --- CUDA extensions (used by cs::cuda::DeviceStereo) ---
  // The buffer's memory: where it was allocated. Within a frame (and a kernel called
  // outside one) the backend may move a buffer to memory it holds for another role rather
  // than copying it back; every frame ends with every buffer back in its own memory, and
  // this call brings a buffer moved outside a frame back (enqueued on the stream).
  float* devicePointer(const Buffer& b);
  CUstream_st* stream() const { return stream_; }
  // Enqueues the copies and fills still queued (they are otherwise enqueued with the next
  // call that needs them), so that everything asked for so far is on the stream.
  void enqueueQueued() { flush(); }
  // dst = the packed float image at src (device memory, rows srcPitchBytes apart), async.
  void copyFromDevice(const Buffer& dst, const float* src, size_t srcPitchBytes);
  // Whether primal-dual iterations may run five per launch on levels whose tiles then fit
  // on the device at once (default on). Off, every level launches once per two iterations
  // (the path of large levels, e.g. to test it on small ones).
  void setFiveIterationLaunches(bool on) { fiveIterationLaunches_ = on; }

 protected:
  Buffer doCreate(int width, int height, int channels) override;
  void doUpload(const Buffer& dst, const float* host, bool* finite) override;
  void doUploadBytes(const Buffer& dst, const uint8_t* host) override;
  void doDownload(const Buffer& src, float* host) override;
  void doDownloadAll(const std::vector<Download>& downloads) override;
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
  // Fused: the first iteration reads u, v in place of the copies uBar = u, vBar = v.
  void doWarpIterations(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                        const Buffer& steps, const Buffer& mask, const PrimalDualParams& params) override;
  // Fused: median + accumulate (+ the next warp's derivatives) in one pass.
  void doWarpTail(const WarpBuffers& warp, const Buffer& medianScratch, float duMax, bool nextWarp) override;
  void doSweepWarp(const Buffer& volume, const Buffer& image, const Buffer& mask, const SweepParams& p) override;
  void doSweepCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& mask,
                   const SweepParams& p) override;
  void doSweepAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                        const SweepParams& p) override;
  void doSweepSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                     const SweepParams& p) override;
  void doSweepInitialise(const Buffer& u, const Buffer& w, const Buffer& confidence, const Buffer& best,
                         const Buffer& other, const Buffer& mask, const SweepParams& p,
                         const ConsistencyParams& c) override;
  void doSweepBandWarp(const Buffer& volume, const Buffer& first, const Buffer& image, const Buffer& coarseBest,
                       const Buffer& mask, const SweepParams& p, float coarseScale) override;
  void doSweepBandCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& first,
                       const Buffer& mask, const SweepParams& p) override;
  void doSweepBandAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& first, const Buffer& mask,
                            const SweepParams& p) override;
  void doSweepBandSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& first,
                         const Buffer& mask, const SweepParams& p) override;
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
  struct Slot {
    float* dev = nullptr;
    float* pinned = nullptr;       // host staging, allocated at the first transfer
    CUevent_st* staged = nullptr;  // completes when the last upload from `pinned` is done
    float* home = nullptr;         // the memory allocated for it: dev at every frame's start and end
    uint8_t* bytes = nullptr;      // device copy of an uploadBytes() image, before its conversion
    Buffer buffer;
  };
  struct PrimalDualScratch {
    float *uBar = nullptr, *vBar = nullptr, *p = nullptr, *q = nullptr, *u = nullptr, *v = nullptr;
  };
  // copy() and fill() are queued and run together as one launch (fewer graph nodes);
  // every other call runs the queue first (flush) so that the stream order is kept.
  struct PendingOp {
    float* dst;
    const float* src;  // null: fill with value
    size_t count;
    float value;
  };
  void enqueue(const PendingOp& op);
  void flush();  // runs the queued ops
  // primal-dual iterations; barsFromPrimals: the first reads u, v in place of uBar, vBar.
  void iterate(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor, const Buffer& steps,
               const Buffer& mask, const PrimalDualParams& params, bool barsFromPrimals);
  // Moves every buffer that holds another's memory back to its own (queued copies).
  void returnBuffersHome();
  float** scratchHolding(const float* memory);
  const Slot& slot(const Buffer& b) const;
  // A buffer's device memory as the kernels take it; OrNone: a null view for an absent one (id -1).
  cudak::Img onDevice(const Buffer& b) const;
  cudak::Img onDeviceOrNone(const Buffer& b) const;
  float* pinnedFor(Slot& s);
  void dropGraph();  // every slot's
  // Every launch goes through check(), which sets lastLaunch_ to Other; the launches that
  // lastLaunch_ names set it after their check().
  void check(int launchResult, const char* what);
  float* scratch(size_t floats, int key);
  float*& scratchSlot(size_t floats, int key);  // the map entry itself, to swap memory with a slot

  int device_ = 0;
  CUstream_st* stream_ = nullptr;
  bool ownsStream_ = false;
  std::string description_;
  unsigned long long memoryBytes_ = 0;
  std::vector<Slot> slots_;
  std::vector<CUevent_st*> downloadEvents_;           // doDownloadAll's, one per piece of the largest call
  std::map<std::pair<int, size_t>, float*> scratch_;  // (role, floats) -> device memory
  std::map<int, PrimalDualScratch> pdScratch_;        // by the id of pd.p
  std::vector<PendingOp> pending_;
  int residentTiledBlocks_ = 0;  // of the tiled primal-dual kernel, on the device at once
  // The kind of the last kernel launched, for kernels that load what it cannot have written
  // before they wait for it: DataTerm (warpDerivatives, accumulate and their fused forms)
  // writes a level's data term, w, u, the tangent and the median, never the mask, tensor or
  // steps; PrimalDual writes the solver state only.
  enum class LastLaunch { Other, DataTerm, PrimalDual };
  LastLaunch lastLaunch_ = LastLaunch::Other;
  bool fiveIterationLaunches_ = true;

  struct FrameRecord {
    CUgraph_st* graph = nullptr;
    CUgraphExec_st* exec = nullptr;
    int issued = 0;  // frames issued (directly or captured) since the buffers were created
  };
  std::array<FrameRecord, kFrameSlots> frames_{};
  int frameSlot_ = -1;  // the slot of the frame being issued (beginFrame .. endFrame), else -1
  bool capturing_ = false;

  bool profiling_ = false;
  std::vector<std::pair<std::string, CUevent_st*>> stageMarks_;
  std::vector<CUevent_st*> eventPool_;
  size_t eventsUsed_ = 0;
};

}  // namespace cuda
}  // namespace cs

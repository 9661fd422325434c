// The Vulkan backend's class (vulkan_backend.hpp describes the backend), shared by its
// sources, one per concern: device.cpp (loader, instance, device choice),
// vulkan_backend.cpp (the logical device), memory.cpp (arenas, parameter blocks,
// transfers), recording.cpp (command buffers, submission, frame replay, timestamps) and
// kernels.cpp (the dispatches of the kernels).
#pragma once
#include <chrono>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "curvestereo/backend.hpp"
#include "device.hpp"
#include "shader_ids.hpp"

namespace cs::vk {

// The shaders (enum Shader, kShaderCount) are generated from backend_vulkan/CMakeLists.txt's
// SHADER_VARIANTS into shader_ids.hpp, in the embedded table's order.

constexpr uint32_t kPushBytes = 128;
constexpr uint32_t kGroup = 16;
// primal_dual.comp's tiles, the largest the device holds: 32 x 32, 32 x 16 or 16 x 16
// cells of 48 bytes of shared memory each.
enum class PdTile { Narrow, Wide, Square };
constexpr uint32_t kPrimalDualCellBytes = 48;

using Addr = uint64_t;

class VulkanBackend final : public Backend {
 public:
  explicit VulkanBackend(const std::string& spec);
  ~VulkanBackend() override;

  std::string name() const override { return "vulkan"; }
  std::string device() const override { return description_; }
  unsigned long long memoryBytes() const override;

  void synchronize() override;
  void beginFrame(int slot) override;
  void endFrame() override;
  bool canReplayFrame(int slot) const override {
    return slot >= 0 && slot < kFrameSlots &&
           (frames_[slot].state == Frame::Running || frames_[slot].state == Frame::Ready);
  }
  void replayFrame(int slot) override;
  void beginStage(const std::string& name) override;
  std::vector<StageTime> takeStageTimes() override;

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
  void doWarpIterations(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                        const Buffer& steps, const Buffer& mask, const PrimalDualParams& params) override;
  void doWarpTail(const WarpBuffers& warp, const Buffer& medianScratch, float duMax, bool nextWarp) override;
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
  struct Arena {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkDeviceAddress address = 0;
    VkDeviceSize size = 0, used = 0;
    void* mapped = nullptr;
  };
  struct Alloc {
    int arena;
    VkDeviceSize offset, bytes;
  };

  void check(VkResult r, const char* what);
  void ensureUsable() const;
  uint32_t memoryType(uint32_t bits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) const;
  // Device: device-local arenas. Staging: host-visible, host-cached where the device has it
  // (the host writes uploads and reads downloads there). Params: host-visible, device-local
  // where the device has it (a GPU's BAR window: every invocation that reads a parameter
  // block reads it from the GPU's memory, not across the bus).
  enum class Memory { Device, Staging, Params };
  Arena makeBuffer(VkDeviceSize bytes, Memory kind);
  void destroyBuffer(Arena& a);
  const Alloc& alloc(const Buffer& b) const;
  Addr addr(const Buffer& b) const;
  Addr paramBlock(const void* data, size_t bytes);
  Addr cameraBlock(const CameraParams& cam0, const double tPrime[3], bool inDouble);
  VkDeviceSize claimStaging(VkDeviceSize bytes);
  void fillByteTable();
  template <class Fill>
  void copyFromStaging(const Buffer& dst, Fill&& fill);
  Addr sweepParamBlock(const SweepParams& p);
  // primalDual (barsFromPrimals false) and warpIterations (true: the first iteration reads
  // u, v as uBar, vBar) in primal_dual.comp's fused dispatches.
  void iterate(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor, const Buffer& steps,
               const Buffer& mask, const PrimalDualParams& params, bool barsFromPrimals);
  VkPipeline pipeline(Shader s);

  VkCommandBuffer recorder();
  // What a command buffer holds last, for the barrier before the next command.
  enum class Cmd { None, Dispatch, Transfer };
  void barrier(VkCommandBuffer cb, Cmd next);
  // src's floats into dst, recorded into cb without a barrier (the caller places one).
  void recordCopy(VkCommandBuffer cb, const Buffer& dst, const Buffer& src);
  void flush();
  void waitFence(VkFence fence, const char* what);
  void abortFrameRecording();
  // Submits one ended command buffer, signalling fence when done.
  void submit(VkCommandBuffer cb, VkFence fence);
  void submitImmediate();
  // A download's piece: its bytes at `staged` in the staging buffer, for `host`.
  struct Piece {
    char* host;
    VkBuffer src;  // the piece's buffer's arena, at srcOffset
    VkDeviceSize srcOffset, staged, bytes;
  };
  std::vector<Piece> downloadPieces(const std::vector<Download>& downloads);
  void recordPieces(const std::vector<Piece>& pieces);
  void copyPiecesOut(const std::vector<Piece>& pieces);
  // A w x h grid of pixels in the 16 x 16 work groups of common.glsl.
  template <class PC>
  void dispatch(Shader s, const PC& pc, int w, int h);
  // groupsX x groupsY work groups, for shaders that map their invocations otherwise.
  template <class PC>
  void dispatchGroups(Shader s, const PC& pc, uint32_t groupsX, uint32_t groupsY);
  // Slots: 0, 1 the structure tensor's blur; 2 the sweeps' direction volumes; 3..8 the
  // primal-dual's spares; kConfidenceTermsScratch the confidence's first pass.
  static constexpr int kConfidenceTermsScratch = 9;
  Buffer scratch(int slot, int w, int h, int channels = 1);

  std::string description_;
  std::shared_ptr<Instance> instance_;  // the process's (sharedInstance)
  const Instance& inst_;
  VkPhysicalDevice phys_ = VK_NULL_HANDLE;
  VkPhysicalDeviceProperties props_{};
  VkPhysicalDeviceMemoryProperties memProps_{};
  bool float64_ = false;                  // the camera models in double (CURVESTEREO_VULKAN_DOUBLE_MODELS)
  bool deviceFloat64_ = false;            // the device has shaderFloat64 (triangulate always uses it)
  PdTile pdTile_ = PdTile::Narrow;        // the largest tile of primal_dual.comp the device holds
  bool subgroupArithmetic_ = false;       // subgroup arithmetic and shuffles in compute shaders
  bool subgroupBallot_ = false;           // subgroup ballots and broadcasts in compute shaders
  uint32_t subgroupSize_ = 1;             // the device's subgroup size (VkPhysicalDeviceSubgroupProperties)
  bool atomicFloatAdd_ = false;           // device_ has float atomic add (panorama_splat's variant)
  std::shared_ptr<SharedDevice> device_;  // shared with the other backends on this GPU
  VkDevice dev_ = VK_NULL_HANDLE;         // device_'s
  VkQueue queue_ = VK_NULL_HANDLE;        // one of device_'s queues, maybe shared
  std::mutex* queueLock_ = nullptr;       // held around queue_'s submissions and waits
  uint32_t queueFamily_ = 0;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkCommandBuffer immCmd_ = VK_NULL_HANDLE;
  VkFence immFence_ = VK_NULL_HANDLE;
  std::vector<VkEvent> pieceEvents_;  // set by a download's piece copies, one per piece (made on first use)
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipelines_[kShaderCount] = {};
  VkQueryPool queryPool_ = VK_NULL_HANDLE;
  uint32_t queryCapacity_ = 0, queryCount_ = 0;
  uint64_t timestampMask_ = ~0ull;
  std::vector<std::string> stampNames_;

  std::vector<Arena> arenas_;
  std::vector<Alloc> allocs_;
  Arena staging_, params_;
  // The byte uploads' device side: stagingMirror_ the staging buffer's size, its regions the
  // bytes copied from the same offsets of staging_; lut_ unitFromByte's 256 floats.
  Arena stagingMirror_, lut_;
  VkDeviceSize paramsUsed_ = 0;
  VkDeviceSize stagingUsed_ = 0;  // by uploads in the immediate command buffer, until flushed
  unsigned long long allocatedBytes_ = 0;
  std::map<std::string, VkDeviceSize> paramCache_;
  std::map<std::tuple<int, int, int, int>, Buffer> scratch_;

  // The recorded frames' command buffers (recording.cpp), one per slot (beginFrame), each
  // with its fence and its own state.
  enum class Frame {
    Empty,           // nothing to replay, nothing in flight
    Recording,       // between beginFrame() and endFrame()
    RecordingTimed,  // the same, holding timestamp writes: it is run once, not replayed
    RunningOnce,     // submitted, not to be replayed (aborted, timed or invalidated)
    Running,         // submitted, replayable
    Ready,           // finished, replayable
  };
  struct FrameSlot {
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    VkFence fence = VK_NULL_HANDLE;  // signalled by the slot's last submission
    Frame state = Frame::Empty;
  };
  // The immediate command buffer (uploads, downloads, kernels outside a frame).
  enum class Immediate { Idle, Recording, InFlight };
  // Hung (a fence timed out) outranks Lost (VK_ERROR_DEVICE_LOST): work may still run.
  enum class Health { Ok, Lost, Hung };
  Cmd lastImm_ = Cmd::None, lastFrame_ = Cmd::None;  // the last command of immCmd_, of the slot being recorded
  FrameSlot frames_[kFrameSlots];
  int recordingSlot_ = -1;  // the slot between beginFrame() and endFrame(), -1 when none
  Immediate imm_ = Immediate::Idle;
  Health health_ = Health::Ok;
  bool recordingFrame() const { return recordingSlot_ >= 0; }
  VkCommandBuffer frameCmd() const { return frames_[recordingSlot_].cmd; }
  // New buffers, a new pose or reused parameter blocks: no recorded frame may be replayed
  // (every slot; a frame being recorded is unaffected: it records the new state).
  void invalidateFrame() {
    for (FrameSlot& f : frames_) {
      if (f.state == Frame::Ready) f.state = Frame::Empty;
      if (f.state == Frame::Running) f.state = Frame::RunningOnce;
    }
  }
  uint64_t timeoutNs_ = 120ull * 1000 * 1000 * 1000;
  // How long the host polls for work to finish before it blocks (CURVESTEREO_VULKAN_SPIN_US;
  // 0 on a CPU device such as lavapipe, whose threads the polling would compete with).
  uint64_t spinNs_ = 0;
};

// Polls ready() until it holds (true) or budgetNs have passed since start (false); ready()
// is asked at least once. The pause between polls spares a hyper-threaded sibling.
template <class Ready>
bool spinUntil(std::chrono::steady_clock::time_point start, uint64_t budgetNs, Ready&& ready) {
  for (;;) {
    if (ready()) return true;
    if (uint64_t(
            std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start).count()) >=
        budgetNs)
      return false;
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    asm volatile("yield");
#endif
  }
}

template <class PC>
void VulkanBackend::dispatch(Shader s, const PC& pc, int w, int h) {
  dispatchGroups(s, pc, (uint32_t(w) + kGroup - 1) / kGroup, (uint32_t(h) + kGroup - 1) / kGroup);
}

template <class PC>
void VulkanBackend::dispatchGroups(Shader s, const PC& pc, uint32_t groupsX, uint32_t groupsY) {
  static_assert(sizeof(PC) <= kPushBytes, "push constants exceed 128 bytes");
  VkPipeline p = pipeline(s);
  VkCommandBuffer cb = recorder();
  uint8_t bytes[kPushBytes] = {};
  std::memcpy(bytes, &pc, sizeof(PC));
  barrier(cb, Cmd::Dispatch);
  inst_.fn.vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_COMPUTE, p);
  inst_.fn.vkCmdPushConstants(cb, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, kPushBytes, bytes);
  inst_.fn.vkCmdDispatch(cb, groupsX, groupsY, 1);
}

}  // namespace cs::vk

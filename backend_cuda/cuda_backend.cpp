#include "cuda_backend.hpp"

#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "curvestereo/camera.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/parallel.hpp"
#include "kernels.hpp"

namespace cs {

namespace {

[[noreturn]] void fail(const std::string& what, cudaError_t e) {
  throw Error("cuda backend: " + what + ": " + cudaGetErrorName(e) + " (" + cudaGetErrorString(e) + ")");
}

void ok(cudaError_t e, const char* what) {
  if (e != cudaSuccess) fail(what, e);
}

// "" or a decimal index; -1 when the text is not one.
int parseDeviceIndex(const std::string& device) {
  if (device.empty()) return 0;
  if (!std::all_of(device.begin(), device.end(), [](char c) { return c >= '0' && c <= '9'; }) || device.size() > 4)
    return -1;
  return std::stoi(device);
}

std::string versionText(int v) { return std::to_string(v / 1000) + "." + std::to_string((v % 1000) / 10); }

cudak::Img img(float* data, const Buffer& b) { return cudak::Img{data, b.width, b.height, b.channels}; }

static_assert(cudak::kMaxInlineFloats >= kMotionFloats, "the motion is uploaded by its launch");

}  // namespace

std::string probeCuda(const std::string& device) {
  const int index = parseDeviceIndex(device);
  if (index < 0) return "CUDA device selector '" + device + "' is not an index";
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e == cudaErrorInsufficientDriver) {
    // The runtime says this both when the driver is too old and when there is none at
    // all (a machine without an NVIDIA GPU): only the first is worth a driver upgrade.
    int driver = 0, runtime = 0;
    cudaDriverGetVersion(&driver);
    cudaRuntimeGetVersion(&runtime);
    if (driver == 0) return "no CUDA device (no NVIDIA driver is loaded)";
    auto version = [](int v) { return std::to_string(v / 1000) + "." + std::to_string(v % 1000 / 10); };
    return "the NVIDIA driver supports CUDA " + version(driver) + ", older than this build's CUDA runtime " +
           version(runtime);
  }
  if (e == cudaErrorNoDevice || (e == cudaSuccess && count == 0)) return "no CUDA device";
  if (e != cudaSuccess) return std::string("no CUDA device (") + cudaGetErrorString(e) + ")";
  if (index >= count)
    return "CUDA device " + std::to_string(index) + " requested but " + std::to_string(count) + " present";
  cudaDeviceProp prop{};
  if (cudaGetDeviceProperties(&prop, index) != cudaSuccess) return "cannot query CUDA device " + std::to_string(index);
  if (prop.major * 10 + prop.minor < 75)
    return std::string(prop.name) + " (sm_" + std::to_string(prop.major * 10 + prop.minor) +
           ") is older than the oldest architecture this build targets (sm_75)";
  return "";
}

std::unique_ptr<Backend> createCudaBackend(const std::string& device) {
  const std::string why = probeCuda(device);
  if (!why.empty()) throw Error("cuda backend: " + why);
  return std::make_unique<cuda::CudaBackend>(parseDeviceIndex(device));
}

namespace cuda {

CudaBackend::CudaBackend(int device, CUstream_st* stream) : device_(device), stream_(stream) {
  ok(cudaSetDevice(device_), "cudaSetDevice");
  if (!stream_) {
    ok(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking), "cudaStreamCreate");
    ownsStream_ = true;
  }
  cudaDeviceProp prop{};
  ok(cudaGetDeviceProperties(&prop, device_), "cudaGetDeviceProperties");
  memoryBytes_ = prop.totalGlobalMem;
  int runtime = 0, driver = 0;
  cudaRuntimeGetVersion(&runtime);
  cudaDriverGetVersion(&driver);
  char memory[32];
  std::snprintf(memory, sizeof memory, "%.1f GiB", double(prop.totalGlobalMem) / (1024.0 * 1024.0 * 1024.0));
  description_ = std::string(prop.name) + " (sm_" + std::to_string(prop.major * 10 + prop.minor) + ", " +
                 std::to_string(prop.multiProcessorCount) + " SMs, " + memory + "), CUDA runtime " +
                 versionText(runtime) + ", driver " + versionText(driver);
  residentTiledBlocks_ = cudak::primalDualTiledResidentBlocks(device_);
}

CudaBackend::~CudaBackend() {
  cudaSetDevice(device_);
  pending_.clear();
  if (capturing_) {
    cudaGraph_t g = nullptr;
    cudaStreamEndCapture(stream_, &g);
    if (g) cudaGraphDestroy(g);
  }
  cudaStreamSynchronize(stream_);
  dropGraph();
  for (Slot& s : slots_) {
    cudaFree(s.dev);
    if (s.pinned) cudaFreeHost(s.pinned);
    cudaFree(s.bytes);
    if (s.staged) cudaEventDestroy(s.staged);
  }
  for (cudaEvent_t e : downloadEvents_) cudaEventDestroy(e);
  for (auto& kv : scratch_) cudaFree(kv.second);
  for (auto& kv : pdScratch_) {
    cudaFree(kv.second.uBar);
    cudaFree(kv.second.vBar);
    cudaFree(kv.second.p);
    cudaFree(kv.second.q);
    cudaFree(kv.second.u);
    cudaFree(kv.second.v);
  }
  for (CUevent_st* e : eventPool_) cudaEventDestroy(e);
  if (ownsStream_) cudaStreamDestroy(stream_);
}

void CudaBackend::check(int launchResult, const char* what) {
  lastLaunch_ = LastLaunch::Other;
  if (launchResult != cudaSuccess) fail(std::string("kernel ") + what, cudaError_t(launchResult));
}

// Backend has checked every kernel's buffers; this check is for the CUDA extensions
// (devicePointer, copyFromDevice), and the memory trades (primal-dual, warp tail) need the
// exact shape of the allocation.
const CudaBackend::Slot& CudaBackend::slot(const Buffer& b) const {
  if (b.id < 0 || size_t(b.id) >= slots_.size()) throw Error("cuda backend: unknown buffer");
  const Slot& s = slots_[size_t(b.id)];
  if (s.buffer.width != b.width || s.buffer.height != b.height || s.buffer.channels != b.channels)
    throw Error("cuda backend: buffer does not match its allocation");
  return s;
}

cudak::Img CudaBackend::onDevice(const Buffer& b) const { return img(slot(b).dev, b); }

cudak::Img CudaBackend::onDeviceOrNone(const Buffer& b) const {
  return b.id >= 0 ? onDevice(b) : cudak::Img{nullptr, 0, 0, 0};
}

float* CudaBackend::devicePointer(const Buffer& b) {
  const Slot& s = slot(b);
  if (s.dev != s.home) {  // moved by a kernel called outside a frame
    returnBuffersHome();
    flush();
  }
  return s.home;
}

float** CudaBackend::scratchHolding(const float* memory) {
  for (auto& kv : pdScratch_)
    for (float** f : {&kv.second.uBar, &kv.second.vBar, &kv.second.p, &kv.second.q, &kv.second.u, &kv.second.v})
      if (*f == memory) return f;
  for (auto& kv : scratch_)
    if (kv.second == memory) return &kv.second;
  return nullptr;
}

// Buffers only ever trade memory with scratch roles (primalDual, warpTail), whose contents
// between calls do not matter: copy the buffer home and trade back. Frames end with every
// buffer home, so that the memory a recorded frame reads at its start (the inputs, a
// sequence's carried state, the estimate a warm frame keeps where its check fails) and
// where it leaves its results are the same for every slot's graph and for the host's view.
// Only buffers whose last call left them in a scratch role's memory are copied (at most a
// level's solver state: 12 floats a pixel).
void CudaBackend::returnBuffersHome() {
  // A buffer's home may be held by another buffer that took it from a scratch role since
  // (same-size buffers share roles): that one goes home first, on a later pass.
  for (bool progress = true; progress;) {
    progress = false;
    bool left = false;
    for (Slot& s : slots_) {
      if (s.dev == s.home) continue;
      float** holder = scratchHolding(s.home);
      if (!holder) {
        left = true;
        continue;
      }
      enqueue({s.home, s.dev, s.buffer.count(), 0.f});
      *holder = s.dev;
      s.dev = s.home;
      progress = true;
    }
    if (!left) return;
  }
  throw Error("cuda backend: lost track of a buffer's memory");
}

float* CudaBackend::pinnedFor(Slot& s) {
  if (!s.pinned) {
    void* p = nullptr;
    ok(cudaMallocHost(&p, s.buffer.count() * sizeof(float)), "cudaMallocHost");
    s.pinned = static_cast<float*>(p);
    ok(cudaEventCreateWithFlags(&s.staged, cudaEventDisableTiming), "cudaEventCreate");
  }
  return s.pinned;
}

float*& CudaBackend::scratchSlot(size_t floats, int key) {
  float*& p = scratch_[{key, floats}];
  if (!p) ok(cudaMalloc(&p, floats * sizeof(float)), "cudaMalloc (scratch)");
  return p;
}

float* CudaBackend::scratch(size_t floats, int key) { return scratchSlot(floats, key); }

void CudaBackend::enqueue(const PendingOp& op) {
  // Ops of one launch run concurrently: queue only what touches none of the buffers the
  // queued ops write (and writes none they read).
  for (const PendingOp& o : pending_)
    if (o.dst == op.dst || (op.src && o.dst == op.src) || (o.src && o.src == op.dst)) {
      flush();
      break;
    }
  if (int(pending_.size()) == cudak::kMaxMemOps) flush();
  pending_.push_back(op);
}

void CudaBackend::flush() {
  if (pending_.empty()) return;
  cudak::MemOps ops{};
  ops.count = int(pending_.size());
  for (size_t i = 0; i < pending_.size(); ++i)
    ops.op[i] = cudak::MemOp{pending_[i].dst, pending_[i].src, pending_[i].count, pending_[i].value};
  pending_.clear();
  check(cudak::launchMemOps(stream_, ops), "copy/fill");
}

void CudaBackend::dropGraph() {
  for (FrameRecord& f : frames_) {
    if (f.exec) cudaGraphExecDestroy(f.exec);
    if (f.graph) cudaGraphDestroy(f.graph);
    f.exec = nullptr;
    f.graph = nullptr;
  }
}

Buffer CudaBackend::doCreate(int width, int height, int channels) {
  ok(cudaSetDevice(device_), "cudaSetDevice");
  flush();
  Slot s;
  s.buffer = Buffer{int(slots_.size()), width, height, channels};
  ok(cudaMalloc(&s.dev, s.buffer.count() * sizeof(float)), "cudaMalloc");
  ok(cudaMemsetAsync(s.dev, 0, s.buffer.count() * sizeof(float), stream_), "cudaMemsetAsync");
  s.home = s.dev;
  slots_.push_back(s);
  // New buffers mean a new pipeline: record its frames afresh.
  dropGraph();
  for (FrameRecord& f : frames_) f.issued = 0;
  return s.buffer;
}

void CudaBackend::doUpload(const Buffer& dst, const float* host, bool* finite) {
  flush();
  Slot& s = slots_[size_t(slot(dst).buffer.id)];
  if (dst.count() <= size_t(cudak::kMaxInlineFloats)) {
    // Small (a sequence's motion, every frame): carried by the launch, so the host never
    // waits for a staging area the stream has not yet read.
    cudak::InlineFloats values{};
    values.count = int(dst.count());
    copyFloats(values.value, host, dst.count(), finite);
    check(cudak::launchSetFloats(stream_, s.dev, values), "upload");
    return;
  }
  float* staging = pinnedFor(s);
  ok(cudaEventSynchronize(s.staged), "cudaEventSynchronize");  // the previous upload left the staging area
  const size_t bytes = dst.count() * sizeof(float);
  copyFloats(staging, host, dst.count(), finite);
  ok(cudaMemcpyAsync(s.dev, staging, bytes, cudaMemcpyHostToDevice, stream_), "upload");
  ok(cudaEventRecord(s.staged, stream_), "cudaEventRecord");
}

// The bytes cross the bus and are converted by a kernel: a quarter of a float image's
// copy into the staging memory and of its transfer.
void CudaBackend::doUploadBytes(const Buffer& dst, const uint8_t* host) {
  flush();
  Slot& s = slots_[size_t(slot(dst).buffer.id)];
  const size_t n = dst.count();
  if (!s.bytes) ok(cudaMalloc(&s.bytes, n), "cudaMalloc (byte upload)");
  uint8_t* staging = reinterpret_cast<uint8_t*>(pinnedFor(s));
  ok(cudaEventSynchronize(s.staged), "cudaEventSynchronize");  // the previous upload left the staging area
  copyBytes(staging, host, n);
  ok(cudaMemcpyAsync(s.bytes, staging, n, cudaMemcpyHostToDevice, stream_), "upload");
  ok(cudaEventRecord(s.staged, stream_), "cudaEventRecord");
  check(cudak::launchFloatsFromBytes(stream_, s.dev, s.bytes, n), "upload (bytes to floats)");
}

void CudaBackend::doDownload(const Buffer& src, float* host) { doDownloadAll({{src, host}}); }

// Every transfer queued at once, in pieces of at most kDownloadPiece floats each followed by
// an event. The host's threads (detail::parallelFor) take the pieces in order, each waiting
// for its event and copying it out of the pinned staging memory while the next ones are
// still crossing the bus: the copies out overlap the transfers and each other.
constexpr size_t kDownloadPiece = size_t(1) << 16;  // 256 KiB

void CudaBackend::doDownloadAll(const std::vector<Download>& downloads) {
  flush();
  struct Piece {
    float* host;
    const float* staged;
    size_t floats;
  };
  std::vector<Piece> pieces;
  for (const Download& d : downloads) {
    Slot& s = slots_[size_t(slot(d.src).buffer.id)];
    float* staging = pinnedFor(s);
    for (size_t at = 0; at < d.src.count(); at += kDownloadPiece) {
      const size_t n = std::min(kDownloadPiece, d.src.count() - at);
      ok(cudaMemcpyAsync(staging + at, s.dev + at, n * sizeof(float), cudaMemcpyDeviceToHost, stream_), "download");
      if (downloadEvents_.size() <= pieces.size()) {
        cudaEvent_t e = nullptr;
        ok(cudaEventCreateWithFlags(&e, cudaEventDisableTiming), "cudaEventCreate");
        downloadEvents_.push_back(e);
      }
      ok(cudaEventRecord(downloadEvents_[pieces.size()], stream_), "cudaEventRecord");
      pieces.push_back({d.host + at, staging + at, n});
    }
  }
  // A worker may not throw: its errors are checked after. It makes this backend's device its
  // own first: a pool thread's first CUDA call would otherwise open a context on device 0.
  std::vector<cudaError_t> waited(pieces.size(), cudaSuccess);
  detail::parallelFor(int(pieces.size()), [&](int i) {
    waited[size_t(i)] = cudaSetDevice(device_);
    if (waited[size_t(i)] == cudaSuccess) waited[size_t(i)] = cudaEventSynchronize(downloadEvents_[size_t(i)]);
    if (waited[size_t(i)] == cudaSuccess)
      std::memcpy(pieces[size_t(i)].host, pieces[size_t(i)].staged, pieces[size_t(i)].floats * sizeof(float));
  });
  for (cudaError_t e : waited) ok(e, "download (synchronize)");
}

void CudaBackend::copyFromDevice(const Buffer& dst, const float* src, size_t srcPitchBytes) {
  flush();
  const size_t rowBytes = size_t(dst.width) * dst.channels * sizeof(float);
  ok(cudaMemcpy2DAsync(slot(dst).dev, rowBytes, src, srcPitchBytes ? srcPitchBytes : rowBytes, rowBytes,
                       size_t(dst.height), cudaMemcpyDeviceToDevice, stream_),
     "copy from device");
}

void CudaBackend::doFill(const Buffer& dst, float value) { enqueue({slot(dst).dev, nullptr, dst.count(), value}); }

void CudaBackend::doCopy(const Buffer& dst, const Buffer& src) {
  float* d = slot(dst).dev;
  const float* s = slot(src).dev;
  if (d != s) enqueue({d, s, dst.count(), 0.f});
}

void CudaBackend::doFields(const Buffer& mask, const Buffer& calibration, const Buffer& trajectory,
                           const FieldsParams& p) {
  flush();
  // t' = R^T t and its direction, as fieldsAtPixel computes them (Eigen, double).
  const Eigen::Matrix3d R = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(p.R);
  const Eigen::Vector3d tPrime = R.transpose() * Eigen::Vector3d(p.t[0], p.t[1], p.t[2]);
  const Eigen::Vector3d dir = tPrime.normalized();
  cudak::FieldsBaseline baseline{};
  for (int i = 0; i < 3; ++i) baseline.tPrime[i] = tPrime[i], baseline.direction[i] = dir[i];
  check(cudak::launchFields(stream_, onDevice(mask), onDevice(calibration), onDevice(trajectory), p, baseline),
        "fields");
  dropGraph();  // a new pose changes the frame's parameters (t' of triangulate)
}

void CudaBackend::doTriangulate(const Buffer& radial, const Buffer& points, const Buffer& w, const Buffer& mask,
                                const CameraParams& cam0, const double tPrime[3]) {
  flush();
  check(
      cudak::launchTriangulate(stream_, onDevice(radial), onDevice(points), onDevice(w), onDevice(mask), cam0, tPrime),
      "triangulate");
}

void CudaBackend::doCarryEstimate(const Buffer& dst, const Buffer& src, const Buffer& guess, const Buffer& motion,
                                  const Buffer& mask, const CarryParams& p) {
  flush();
  const cudak::Img guessImg = onDeviceOrNone(guess);
  check(
      cudak::launchCarryEstimate(stream_, onDevice(dst), onDevice(src), guessImg, slot(motion).dev, onDevice(mask), p),
      "carryEstimate");
}

void CudaBackend::doTemporalFilter(const Buffer& state, const Buffer& u, const Buffer& w, const Buffer& prior,
                                   const Buffer& radial, const Buffer& points, const Buffer& confidence,
                                   const Buffer& mask, const TemporalParams& p) {
  flush();
  const cudak::Img weight = onDeviceOrNone(confidence);
  check(cudak::launchTemporalFilter(stream_, onDevice(state), onDevice(u), onDevice(w), onDevice(prior),
                                    onDevice(radial), onDevice(points), weight, onDevice(mask), p),
        "temporalFilter");
}

void CudaBackend::doFinishResult(const Buffer& valid, const Buffer& z, const Buffer& radial, const Buffer& points,
                                 const Buffer& disparity, const Buffer& warp, const Buffer& confidence) {
  flush();
  check(cudak::launchFinishResult(stream_, onDevice(valid), onDevice(z), onDevice(radial), onDevice(points),
                                  onDevice(disparity), onDevice(warp), onDevice(confidence)),
        "finishResult");
}

void CudaBackend::doPlainSupport(const Buffer& support, const Buffer& confidence, const Buffer& w, const Buffer& mask,
                                 const Buffer& levelImage, const Buffer& levelMask) {
  flush();
  check(cudak::launchPlainSupport(stream_, onDevice(support), onDevice(confidence), onDevice(w), onDevice(mask),
                                  onDevice(levelImage), onDevice(levelMask)),
        "plainSupport");
}

void CudaBackend::doFillPlanes(const Buffer& u, const Buffer& w, const Buffer& planeConfidence, const Buffer& labels,
                               const Buffer& planes, const Buffer& mask, const CameraParams& cam0,
                               const double tPrime[3]) {
  flush();
  check(cudak::launchFillPlanes(stream_, onDevice(u), onDevice(w), onDevice(planeConfidence), onDevice(labels),
                                onDevice(planes), onDevice(mask), cam0, tPrime),
        "fillPlanes");
}

void CudaBackend::doPanoramaPlace(const Buffer& place, const Buffer& radial, const Buffer& rays,
                                  const PanoramaParams& p) {
  flush();
  check(cudak::launchPanoramaPlace(stream_, onDevice(place), onDevice(radial), onDevice(rays), p), "panoramaPlace");
}

void CudaBackend::doPanoramaSplat(const Buffer& accum, const Buffer& place, const Buffer& confidence,
                                  const Buffer& grey, const PanoramaParams& p) {
  flush();
  check(cudak::launchPanoramaSplat(stream_, onDevice(accum), onDevice(place), onDevice(confidence),
                                   onDeviceOrNone(grey), p),
        "panoramaSplat");
}

void CudaBackend::doPanoramaResolve(const Buffer& range, const Buffer& grey, const Buffer& confidence,
                                    const Buffer& accum) {
  flush();
  check(cudak::launchPanoramaResolve(stream_, onDevice(range), onDevice(grey), onDevice(confidence), onDevice(accum)),
        "panoramaResolve");
}

void CudaBackend::doRoundTrip(const Buffer& error, const Buffer& w, const Buffer& calibration, const Buffer& reverseW,
                              const Buffer& reverseCalibration, const Buffer& reverseMask, const Buffer& mask) {
  flush();
  check(cudak::launchRoundTrip(stream_, onDevice(error), onDevice(w), onDevice(calibration), onDevice(reverseW),
                               onDevice(reverseCalibration), onDevice(reverseMask), onDevice(mask)),
        "roundTrip");
}

// The scratch role of resultConfidence's per-pixel terms (4 floats a pixel); 0-3 are the
// other kernels'.
constexpr int kConfidenceTermsKey = 4;

void CudaBackend::doResultConfidence(const Buffer& confidence, const Buffer& radial, const Buffer& points,
                                     const Buffer& image, const Buffer& n0, const Buffer& n1, const Buffer& w,
                                     const Buffer& trajectory, const Buffer& sweepConfidence,
                                     const Buffer& roundTripError, const Buffer& planeConfidence, const Buffer& mask,
                                     const ConfidenceParams& p) {
  flush();
  check(cudak::launchResultConfidence(stream_, onDevice(confidence), onDevice(radial), onDevice(points),
                                      onDevice(image), onDevice(n0), onDevice(n1), onDevice(w), onDevice(trajectory),
                                      onDeviceOrNone(sweepConfidence), onDeviceOrNone(roundTripError),
                                      onDeviceOrNone(planeConfidence), onDevice(mask), p,
                                      scratch(4 * mask.count(), kConfidenceTermsKey)),
        "resultConfidence");
}

void CudaBackend::doSweepWarp(const Buffer& volume, const Buffer& image, const Buffer& mask, const SweepParams& p) {
  flush();
  check(cudak::launchSweepWarp(stream_, onDevice(volume), onDevice(image), onDevice(mask), p), "sweepWarp");
}

void CudaBackend::doSweepCost(const Buffer& costs, const Buffer& reference, const Buffer& volume, const Buffer& mask,
                              const SweepParams& p) {
  flush();
  check(cudak::launchSweepCost(stream_, onDevice(costs), onDevice(reference), onDevice(volume), onDevice(mask), p),
        "sweepCost");
}

void CudaBackend::doSweepAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                                   const SweepParams& p) {
  flush();
  // The three directions walked beside +x need a buffer each (scratch, kept for the next frame).
  const cudak::Img spare{scratch(3 * aggregated.count(), 3), aggregated.width, aggregated.height, aggregated.channels};
  check(cudak::launchSweepAggregate(stream_, onDevice(aggregated), spare, onDevice(costs), onDevice(mask), p),
        "sweepAggregate");
}

void CudaBackend::doSweepSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs, const Buffer& mask,
                                const SweepParams& p) {
  flush();
  check(cudak::launchSweepSelect(stream_, onDevice(best), onDevice(aggregated), onDevice(costs), onDevice(mask), p),
        "sweepSelect");
}

void CudaBackend::doSweepInitialise(const Buffer& u, const Buffer& w, const Buffer& confidence, const Buffer& best,
                                    const Buffer& other, const Buffer& mask, const SweepParams& p,
                                    const ConsistencyParams& c) {
  flush();
  check(cudak::launchSweepInitialise(stream_, onDevice(u), onDevice(w), onDevice(confidence), onDevice(best),
                                     onDevice(other), onDevice(mask), p, c),
        "sweepInitialise");
}

void CudaBackend::doSweepBandWarp(const Buffer& volume, const Buffer& first, const Buffer& image,
                                  const Buffer& coarseBest, const Buffer& mask, const SweepParams& p,
                                  float coarseScale) {
  flush();
  check(cudak::launchSweepBandWarp(stream_, onDevice(volume), onDevice(first), onDevice(image), onDevice(coarseBest),
                                   onDevice(mask), p, coarseScale),
        "sweepBandWarp");
}

void CudaBackend::doSweepBandCost(const Buffer& costs, const Buffer& reference, const Buffer& volume,
                                  const Buffer& first, const Buffer& mask, const SweepParams& p) {
  flush();
  check(cudak::launchSweepBandCost(stream_, onDevice(costs), onDevice(reference), onDevice(volume), onDevice(first),
                                   onDevice(mask), p),
        "sweepBandCost");
}

void CudaBackend::doSweepBandAggregate(const Buffer& aggregated, const Buffer& costs, const Buffer& first,
                                       const Buffer& mask, const SweepParams& p) {
  flush();
  // As sweepAggregate: the three directions walked beside +x need a buffer each (the same
  // scratch role: the two aggregations never run at once).
  const cudak::Img spare{scratch(3 * aggregated.count(), 3), aggregated.width, aggregated.height, aggregated.channels};
  check(cudak::launchSweepBandAggregate(stream_, onDevice(aggregated), spare, onDevice(costs), onDevice(first),
                                        onDevice(mask), p),
        "sweepBandAggregate");
}

void CudaBackend::doSweepBandSelect(const Buffer& best, const Buffer& aggregated, const Buffer& costs,
                                    const Buffer& first, const Buffer& mask, const SweepParams& p) {
  flush();
  check(cudak::launchSweepBandSelect(stream_, onDevice(best), onDevice(aggregated), onDevice(costs), onDevice(first),
                                     onDevice(mask), p),
        "sweepBandSelect");
}

void CudaBackend::doWarp(const Buffer& dst, const Buffer& src, const Buffer& flow) {
  flush();
  check(cudak::launchWarp(stream_, onDevice(dst), onDevice(src), onDevice(flow)), "warp");
}

void CudaBackend::doDownsample(const Buffer& dst, const Buffer& src, float scale) {
  flush();
  check(cudak::launchDownsample(stream_, onDevice(dst), onDevice(src), scale), "downsample");
}

void CudaBackend::doUpsample(const Buffer& dst, const Buffer& src, float scale, float valueScale) {
  flush();
  check(cudak::launchUpsample(stream_, onDevice(dst), onDevice(src), scale, valueScale), "upsample");
}

void CudaBackend::doUpsampleEstimate(const Buffer& u, const Buffer& w, const Buffer& coarseU, const Buffer& coarseW,
                                     const Buffer& n0, const Buffer& n1, const Buffer& mask,
                                     const EstimateUpsampleParams& p) {
  flush();
  auto dev = [&](const Buffer& b) { return onDevice(b); };
  check(cudak::launchUpsampleEstimate(stream_, dev(u), dev(w), dev(coarseU), dev(coarseW), dev(n0), dev(n1), dev(mask),
                                      p),
        "upsampleEstimate");
}

void CudaBackend::doNormalise(const Buffer& dst, const Buffer& moments, const Buffer& src, const Buffer& mask,
                              const NormaliseParams& p) {
  flush();
  check(cudak::launchNormalise(stream_, onDevice(dst), onDevice(moments), onDevice(src), onDevice(mask), p),
        "normalise");
}

void CudaBackend::doStructureTensor(const Buffer& tensor, const Buffer& steps, const Buffer& image, const Buffer& mask,
                                    const TensorParams& p) {
  flush();
  cudak::TensorTaps taps{};
  taps.radius = -1;
  if (p.sigma > 0.f) {
    // The oracle's taps; radius <= kMaxTensorRadius (Backend checked).
    const std::vector<float> t = gaussianTaps(p.sigma);
    std::copy(t.begin(), t.end(), taps.taps);
    taps.radius = int(t.size() / 2);
  }
  const size_t n = size_t(image.width) * image.height;
  check(cudak::launchStructureTensor(stream_, onDevice(tensor), onDevice(steps), onDevice(image), onDevice(mask), p,
                                     taps, scratch(n, 0), scratch(n, 1)),
        "structureTensor");
}

namespace {

// What warpDerivatives writes besides u0 and reads besides w and u.
cudak::DataTermOut dataTermOut(const cudak::Img& iu, const cudak::Img& iz, const cudak::Img& tangent) {
  return {iu, iz, tangent};
}

}  // namespace

void CudaBackend::doWarpDerivatives(const DataTermBuffers& data, const Buffer& tangent, const Buffer& i0,
                                    const Buffer& i1, const Buffer& trajectory, const Buffer& w, const Buffer& u,
                                    const Buffer& mask, const Buffer& confidence, float weightFloor) {
  flush();
  const cudak::Img weight = onDeviceOrNone(confidence);
  const cudak::DataTermOut out = dataTermOut(onDevice(data.iu), onDevice(data.iz), onDevice(tangent));
  const cudak::DataTermIn in{onDevice(i0), onDevice(i1), onDevice(trajectory), onDevice(mask), weight, weightFloor};
  check(cudak::launchWarpDerivatives(stream_, onDevice(data.u0), out, in, onDevice(w), onDevice(u)), "warpDerivatives");
  lastLaunch_ = LastLaunch::DataTerm;
}

void CudaBackend::doPrimalDual(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                               const Buffer& steps, const Buffer& mask, const PrimalDualParams& params) {
  iterate(pd, data, tensor, steps, mask, params, false);
}

void CudaBackend::doWarpIterations(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                                   const Buffer& steps, const Buffer& mask, const PrimalDualParams& params) {
  iterate(pd, data, tensor, steps, mask, params, true);
}

void CudaBackend::iterate(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                          const Buffer& steps, const Buffer& mask, const PrimalDualParams& params,
                          bool barsFromPrimals) {
  flush();
  const int w = mask.width, h = mask.height;
  const size_t n = size_t(w) * h;
  PrimalDualScratch& b = pdScratch_[pd.p.id];
  if (!b.uBar) {
    ok(cudaMalloc(&b.uBar, n * sizeof(float)), "cudaMalloc (primal-dual)");
    ok(cudaMalloc(&b.vBar, 2 * n * sizeof(float)), "cudaMalloc (primal-dual)");
    ok(cudaMalloc(&b.p, 2 * n * sizeof(float)), "cudaMalloc (primal-dual)");
    ok(cudaMalloc(&b.q, 4 * n * sizeof(float)), "cudaMalloc (primal-dual)");
    ok(cudaMalloc(&b.u, n * sizeof(float)), "cudaMalloc (primal-dual)");
    ok(cudaMalloc(&b.v, 2 * n * sizeof(float)), "cudaMalloc (primal-dual)");
  }
  cudak::PrimalDualDev d{};
  d.u[0] = slot(pd.u).dev, d.u[1] = b.u;
  d.v[0] = slot(pd.v).dev, d.v[1] = b.v;
  d.uBar[0] = slot(pd.uBar).dev, d.uBar[1] = b.uBar;
  d.vBar[0] = slot(pd.vBar).dev, d.vBar[1] = b.vBar;
  d.p[0] = slot(pd.p).dev, d.p[1] = b.p;
  d.q[0] = slot(pd.q).dev, d.q[1] = b.q;
  d.uBarFirst = barsFromPrimals ? d.u[0] : d.uBar[0];
  d.vBarFirst = barsFromPrimals ? d.v[0] : d.vBar[0];
  d.u0 = slot(data.u0).dev, d.iu = slot(data.iu).dev, d.iz = slot(data.iz).dev;
  d.tensor = slot(tensor).dev, d.steps = slot(steps).dev, d.mask = slot(mask).dev;
  d.width = w, d.height = h;
  d.weights = params;
  std::vector<cudak::DeviceStep> schedule;
  for (const PrimalDualStep& s : params.schedule) {
    const float sigmaQ = s.sigmaScale * 0.5f / params.alpha0;  // as cpu/primal_dual.cpp
    schedule.push_back({s, sigmaQ * params.alpha0});
  }
  if (schedule.empty()) {  // no iteration to read u, v in their place: the copies themselves
    if (barsFromPrimals) doCopy(pd.uBar, pd.u), doCopy(pd.vBar, pd.v);
    return;
  }
  int endSet = 0;
  check(cudak::launchPrimalDual(stream_, d, schedule.data(), int(schedule.size()),
                                fiveIterationLaunches_ ? residentTiledBlocks_ : 0, lastLaunch_ == LastLaunch::DataTerm,
                                endSet),
        "primalDual");
  lastLaunch_ = LastLaunch::PrimalDual;
  // The result is in the scratch set: it becomes the buffers' memory (later launches,
  // captured or not, take the pointers from the slots), the old memory the scratch set.
  if (endSet == 1) {
    std::swap(slots_[size_t(pd.u.id)].dev, b.u);
    std::swap(slots_[size_t(pd.v.id)].dev, b.v);
    std::swap(slots_[size_t(pd.uBar.id)].dev, b.uBar);
    std::swap(slots_[size_t(pd.vBar.id)].dev, b.vBar);
    std::swap(slots_[size_t(pd.p.id)].dev, b.p);
    std::swap(slots_[size_t(pd.q.id)].dev, b.q);
  }
}

void CudaBackend::doMedian(const Buffer& dst, const Buffer& src, const Buffer& mask) {
  flush();
  check(cudak::launchMedian(stream_, onDevice(dst), onDevice(src), onDevice(mask)), "median");
}

void CudaBackend::doAccumulate(const Buffer& u, const Buffer& w, const Buffer& u0, const Buffer& tangent,
                               const Buffer& mask, float duMax) {
  flush();
  check(cudak::launchAccumulate(stream_, onDevice(u), onDevice(w), onDevice(u0), onDevice(tangent), onDevice(mask),
                                duMax),
        "accumulate");
  lastLaunch_ = LastLaunch::DataTerm;
}

// One pass: each pixel's median, accumulate and (with nextWarp) the next warp's
// derivatives, which all work on the pixel's own u and w. With the median, the pass writes
// the median to medianScratch and the accumulated u to a spare buffer, which then becomes
// u's memory (u is read around each pixel, so it cannot be written in place); without it,
// u is accumulated in place.
void CudaBackend::doWarpTail(const WarpBuffers& warp, const Buffer& medianScratch, float duMax, bool nextWarp) {
  flush();
  const Buffer& u = warp.u;
  const cudak::Img w = onDevice(warp.w), u0 = onDevice(warp.data.u0);
  const cudak::Img tangent = onDevice(warp.tangent), mask = onDevice(warp.mask);
  const cudak::Img weight = onDeviceOrNone(warp.confidence);
  const cudak::DataTermOut nextOut = dataTermOut(onDevice(warp.data.iu), onDevice(warp.data.iz), tangent);
  const cudak::DataTermIn nextIn{onDevice(warp.i0), onDevice(warp.i1), onDevice(warp.trajectory), mask, weight,
                                 warp.weightFloor};
  const cudak::DataTermOut* out = nextWarp ? &nextOut : nullptr;
  const cudak::DataTermIn* in = nextWarp ? &nextIn : nullptr;
  if (medianScratch.id >= 0) {
    float*& spare = scratchSlot(u.count(), 2);
    float* const uIn = slot(u).dev;
    std::swap(slots_[size_t(u.id)].dev, spare);
    check(cudak::launchMedianAccumulate(stream_, onDevice(u), onDevice(medianScratch), img(uIn, u), w, u0, tangent,
                                        mask, duMax, out, in, lastLaunch_ == LastLaunch::PrimalDual),
          nextWarp ? "median + accumulate + derivatives" : "median + accumulate");
  } else {
    check(cudak::launchAccumulate(stream_, onDevice(u), w, u0, tangent, mask, duMax, out, in),
          nextWarp ? "accumulate + derivatives" : "accumulate");
  }
  lastLaunch_ = LastLaunch::DataTerm;
}

void CudaBackend::synchronize() {
  flush();
  ok(cudaStreamSynchronize(stream_), "synchronize");
}

namespace {

void checkFrameSlot(int slot) {
  if (slot < 0 || slot >= kFrameSlots)
    throw Error("cuda backend: frame slot " + std::to_string(slot) + " outside 0.." + std::to_string(kFrameSlots - 1));
}

}  // namespace

void CudaBackend::beginFrame(int slot) {
  checkFrameSlot(slot);
  if (capturing_) {  // a frame that failed while it was recorded: drop what it captured
    cudaGraph_t g = nullptr;
    cudaStreamEndCapture(stream_, &g);
    if (g) cudaGraphDestroy(g);
    capturing_ = false;
  }
  // What was queued outside the frame (a sequence's fill, copy, motion) runs before it and
  // is not recorded; a buffer a kernel called outside a frame moved goes home first.
  returnBuffersHome();
  flush();
  frameSlot_ = slot;
  FrameRecord& f = frames_[size_t(slot)];
  if (profiling_ || f.issued == 0) return;  // run directly
  if (f.exec) cudaGraphExecDestroy(f.exec);
  if (f.graph) cudaGraphDestroy(f.graph);
  f.exec = nullptr;
  f.graph = nullptr;
  ok(cudaStreamBeginCapture(stream_, cudaStreamCaptureModeRelaxed), "cudaStreamBeginCapture");
  capturing_ = true;
}

void CudaBackend::endFrame() {
  returnBuffersHome();
  flush();
  if (frameSlot_ < 0) return;  // no beginFrame: nothing to record
  FrameRecord& f = frames_[size_t(frameSlot_)];
  frameSlot_ = -1;
  ++f.issued;
  if (!capturing_) return;
  capturing_ = false;
  ok(cudaStreamEndCapture(stream_, &f.graph), "cudaStreamEndCapture");
  ok(cudaGraphInstantiate(&f.exec, f.graph, 0), "cudaGraphInstantiate");
  ok(cudaGraphLaunch(f.exec, stream_), "cudaGraphLaunch");
}

bool CudaBackend::canReplayFrame(int slot) const {
  return slot >= 0 && slot < kFrameSlots && frames_[size_t(slot)].exec != nullptr;
}

void CudaBackend::replayFrame(int slot) {
  checkFrameSlot(slot);
  if (!frames_[size_t(slot)].exec)
    throw Error("cuda backend: no recorded frame in slot " + std::to_string(slot) + " to replay");
  // As beginFrame: the queued work first, every buffer where the graph expects it.
  returnBuffersHome();
  flush();
  ok(cudaGraphLaunch(frames_[size_t(slot)].exec, stream_), "cudaGraphLaunch");
}

void CudaBackend::beginStage(const std::string& name) {
  flush();
  profiling_ = true;
  if (eventsUsed_ == eventPool_.size()) {
    cudaEvent_t e = nullptr;
    ok(cudaEventCreate(&e), "cudaEventCreate");
    eventPool_.push_back(e);
  }
  CUevent_st* e = eventPool_[eventsUsed_++];
  ok(cudaEventRecord(e, stream_), "cudaEventRecord");
  stageMarks_.emplace_back(name, e);
}

std::vector<StageTime> CudaBackend::takeStageTimes() {
  std::vector<StageTime> out;
  if (!stageMarks_.empty()) {
    beginStage("");
    ok(cudaEventSynchronize(stageMarks_.back().second), "cudaEventSynchronize");
    for (size_t i = 0; i + 1 < stageMarks_.size(); ++i) {
      float ms = 0.f;
      ok(cudaEventElapsedTime(&ms, stageMarks_[i].second, stageMarks_[i + 1].second), "cudaEventElapsedTime");
      const std::string& name = stageMarks_[i].first;
      auto it = std::find_if(out.begin(), out.end(), [&](const StageTime& s) { return s.name == name; });
      if (it == out.end())
        out.push_back({name, double(ms)});
      else
        it->ms += ms;
    }
  }
  stageMarks_.clear();
  eventsUsed_ = 0;
  profiling_ = false;
  return out;
}

}  // namespace cuda
}  // namespace cs

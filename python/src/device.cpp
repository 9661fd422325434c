// The CUDA path of the Python module: GPU arrays (CuPy, PyTorch) in, NumPy or GPU arrays
// out, through cs::cuda::DeviceStereo, without a round trip through the host.
//
// Per frame, on one private stream: inputs -> packed float gray (our kernel, any dtype
// and strides, NaN check), DeviceStereo::compute (graph replay), the host API's finish pass
// into fresh output buffers (our kernel), then one synchronisation. compute() returns when
// the results are ready, so a result never depends on the caller's stream discipline, and
// input arrays may be reused or freed as soon as it returns.
//
// Lifetime: output buffers are stream-ordered allocations owned by DeviceArray objects
// (shared with every DLPack export of them); they keep the stream they are freed on alive,
// so they may outlive the Stereo. A buffer is freed after the work already queued on the
// legacy default stream (where CuPy and PyTorch work by default): a consumer on another
// stream must keep the array alive until its work is done, as with any CUDA memory.
#include <cuda_runtime_api.h>

#include <chrono>
#include <cstring>
#include <exception>
#include <limits>
#include <mutex>

#include "binding.hpp"
#include "curvestereo/cuda.hpp"
#include "device_kernels.hpp"
#include "dlpack.hpp"

namespace cs::py {

namespace {

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw Error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(e));
}

struct DeviceGuard {
  int previous = -1;
  explicit DeviceGuard(int device) {
    if (cudaGetDevice(&previous) == cudaSuccess && previous != device) cudaSetDevice(device);
  }
  ~DeviceGuard() {
    if (previous >= 0) cudaSetDevice(previous);
  }
};

// The stream of one Stereo's device path, shared with the buffers it handed out.
struct CudaContext {
  int device = 0;
  cudaStream_t stream = nullptr;
  cudaEvent_t event = nullptr;
  std::mutex eventLock;  // one event, recorded from whichever thread frees a buffer

  bool pools = false;  // stream-ordered allocation (cudaMallocAsync) works on this device

  explicit CudaContext(int dev) : device(dev) {
    DeviceGuard guard(device);
    check(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking), "cudaStreamCreate");
    check(cudaEventCreateWithFlags(&event, cudaEventDisableTiming), "cudaEventCreate");
    int supported = 0;
    pools = cudaDeviceGetAttribute(&supported, cudaDevAttrMemoryPoolsSupported, device) == cudaSuccess && supported;
  }
  ~CudaContext() {
    DeviceGuard guard(device);
    if (stream) cudaStreamSynchronize(stream), cudaStreamDestroy(stream);
    if (event) cudaEventDestroy(event);
  }
  // Our stream waits for what is queued on `other` now.
  cudaError_t waitFor(cudaStream_t other) {
    std::lock_guard<std::mutex> lock(eventLock);
    cudaError_t e = cudaEventRecord(event, other);
    return e == cudaSuccess ? cudaStreamWaitEvent(stream, event, 0) : e;
  }
};

// Stream-ordered where the device has memory pools (a frame's allocations cost next to
// nothing), else plain cudaMalloc / cudaFree (which waits for the whole device: safe too).
struct DeviceBuffer {
  std::shared_ptr<CudaContext> ctx;
  void* ptr = nullptr;
  size_t bytes = 0;

  DeviceBuffer(std::shared_ptr<CudaContext> c, size_t n) : ctx(std::move(c)), bytes(n) {
    DeviceGuard guard(ctx->device);
    if (ctx->pools)
      check(cudaMallocAsync(&ptr, bytes ? bytes : 1, ctx->stream), "cudaMallocAsync");
    else
      check(cudaMalloc(&ptr, bytes ? bytes : 1), "cudaMalloc");
  }
  // May run on any thread, with or without the GIL (a DLPack consumer's deleter): CUDA only.
  ~DeviceBuffer() {
    DeviceGuard guard(ctx->device);
    if (ctx->pools) {
      ctx->waitFor(cudaStreamLegacy);
      cudaFreeAsync(ptr, ctx->stream);
    } else {
      cudaFree(ptr);
    }
  }
};

// A result left on the GPU: what CuPy (cupy.asarray / from_dlpack) and PyTorch
// (torch.from_dlpack / as_tensor) wrap without copying.
struct DeviceArray {
  std::shared_ptr<DeviceBuffer> buffer;
  std::vector<long long> shape;
  bool isBool = false;  // else float32

  size_t itemsize() const { return isBool ? 1 : 4; }
  size_t count() const {
    size_t n = 1;
    for (long long s : shape) n *= size_t(s);
    return n;
  }
};

struct Exported {
  DLManagedTensor tensor{};
  std::shared_ptr<DeviceBuffer> buffer;
  int64_t shape[3] = {0, 0, 0};
};

pb::capsule exportDlpack(const DeviceArray& a) {
  auto* e = new Exported;
  e->buffer = a.buffer;
  for (size_t i = 0; i < a.shape.size(); ++i) e->shape[i] = a.shape[i];
  DLTensor& t = e->tensor.dl_tensor;
  t.data = a.buffer->ptr;
  t.device = {kDLCUDA, a.buffer->ctx->device};
  t.ndim = int32_t(a.shape.size());
  t.dtype = a.isBool ? DLDataType{kDLBool, 8, 1} : DLDataType{kDLFloat, 32, 1};
  t.shape = e->shape;
  t.strides = nullptr;  // packed
  t.byte_offset = 0;
  e->tensor.manager_ctx = e;
  e->tensor.deleter = [](DLManagedTensor* self) { delete static_cast<Exported*>(self->manager_ctx); };
  // A consumer renames the capsule to "used_dltensor" and calls the deleter itself; an
  // unconsumed capsule frees the tensor here.
  PyObject* cap = PyCapsule_New(&e->tensor, "dltensor", [](PyObject* capsule) {
    if (!PyCapsule_IsValid(capsule, "dltensor")) return;
    auto* t = static_cast<DLManagedTensor*>(PyCapsule_GetPointer(capsule, "dltensor"));
    if (t && t->deleter) t->deleter(t);
  });
  if (!cap) {
    delete e;
    throw pb::error_already_set();
  }
  return pb::reinterpret_steal<pb::capsule>(cap);
}

pb::dict cudaArrayInterface(const DeviceArray& a) {
  pb::dict d;
  pb::tuple shape(a.shape.size());
  for (size_t i = 0; i < a.shape.size(); ++i) shape[i] = pb::int_(a.shape[i]);
  d["shape"] = shape;
  d["typestr"] = a.isBool ? "|b1" : "<f4";
  d["data"] = pb::make_tuple(reinterpret_cast<uintptr_t>(a.buffer->ptr), false);
  d["version"] = 3;
  d["strides"] = pb::none();
  d["stream"] = pb::none();  // compute() synchronised: nothing to wait for
  return d;
}

pb::array toHost(const DeviceArray& a) {
  std::vector<pb::ssize_t> shape(a.shape.begin(), a.shape.end());
  pb::array out(a.isBool ? pb::dtype::of<bool>() : pb::dtype::of<float>(), shape);
  {
    pb::gil_scoped_release nogil;
    DeviceGuard guard(a.buffer->ctx->device);
    check(cudaMemcpyAsync(out.mutable_data(), a.buffer->ptr, a.count() * a.itemsize(), cudaMemcpyDeviceToHost,
                          a.buffer->ctx->stream),
          "download");
    check(cudaStreamSynchronize(a.buffer->ctx->stream), "download");
  }
  return out;
}

cudaStream_t streamFromInterface(uintptr_t s) {
  if (s == 1) return cudaStreamLegacy;
  if (s == 2) return cudaStreamPerThread;
  return reinterpret_cast<cudaStream_t>(s);
}

int deviceIndex(const std::string& spec) {
  const auto colon = spec.find(':');
  if (colon == std::string::npos) return 0;
  const std::string d = spec.substr(colon + 1);
  if (d.empty() || d.find_first_not_of("0123456789") != std::string::npos)
    return 0;  // a name: DeviceStereo takes indices
  return std::stoi(d);
}

// A width x height image over storage from `pool`, filled from the downloaded bytes at src.
template <class T>
Image<T> pooledCopy(ResultPool& pool, const char* src, int width, int height) {
  Image<T> img;
  img.width = width, img.height = height;
  img.data = pool.take<T>(size_t(width) * size_t(height));
  std::memcpy(static_cast<void*>(img.data.data()), src, img.data.size() * sizeof(T));
  return img;
}

}  // namespace

class DevicePath {
 public:
  DevicePath(const Rig& rig, const Params& params, int device)
      : ctx_(std::make_shared<CudaContext>(device)), width_(rig.cam0.width), height_(rig.cam0.height) {
    DeviceGuard guard(device);
    stereo_ = std::make_unique<cuda::DeviceStereo>(rig, params, ctx_->stream, device);
    const size_t n = size_t(width_) * size_t(height_);
    inputs_ = std::make_shared<DeviceBuffer>(ctx_, 2 * n * sizeof(float));
    flag_ = std::make_shared<DeviceBuffer>(ctx_, sizeof(unsigned));
    check(cudaMallocHost(reinterpret_cast<void**>(&pinnedFlag_), sizeof(unsigned)), "cudaMallocHost");
  }
  ~DevicePath() {
    DeviceGuard guard(ctx_->device);
    cudaStreamSynchronize(ctx_->stream);  // nothing in flight reads or writes the pinned buffers
    for (void* p : {static_cast<void*>(pinnedFlag_), static_cast<void*>(pinnedIn_), pinnedOut_})
      if (p) cudaFreeHost(p);
  }

  void setPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
    DeviceGuard guard(ctx_->device);
    stereo_->setPose(R, t);
  }
  void setMask(const ImageU8& mask) {
    DeviceGuard guard(ctx_->device);
    stereo_->setMask(mask);
  }

  void resetSequence() {
    DeviceGuard guard(ctx_->device);
    stereo_->resetSequence();
  }

  // sequence: DeviceStereo::next (with `pose`), else DeviceStereo::compute.
  Result compute(pb::handle left, pb::handle right, bool returnDevice, const Stereo::Outputs& sel,
                 const std::shared_ptr<ResultPool>& pool, bool sequence = false, const Pose* pose = nullptr) {
    const auto t0 = std::chrono::steady_clock::now();
    const uintptr_t ours = reinterpret_cast<uintptr_t>(ctx_->stream);
    // With the GIL: the protocols and host conversions are Python calls. Host inputs are
    // converted straight into this path's pinned staging buffer (reused every frame).
    Input in[2] = {input(left, "left image", ours, 0), input(right, "right image", ours, 1)};
    const long long n = (long long)width_ * height_;
    Result result;
    std::vector<std::shared_ptr<DeviceBuffer>> buffers;  // every output buffer, in PackArgs order
    PackArgs fa;
    fa.n = n;
    // Device results: fresh buffers each frame (the DeviceArray objects own them). Host
    // results: carved from one device buffer and one pinned buffer kept by this path, so a
    // frame allocates nothing there and downloads in one copy.
    size_t hostBytes = 0;
    std::vector<size_t> offsets;
    auto buffer = [&](size_t bytes) -> void* {
      if (returnDevice) {
        buffers.push_back(std::make_shared<DeviceBuffer>(ctx_, bytes));
        return buffers.back()->ptr;
      }
      offsets.push_back(hostBytes);
      hostBytes += (bytes + 255) / 256 * 256;
      return nullptr;  // placed below, once the total is known
    };
    unsigned flag = 0;
    {
      pb::gil_scoped_release nogil;
      DeviceGuard guard(ctx_->device);
      cudaStream_t s = ctx_->stream;
      // On an error part-way, wait for what was queued before the inputs are let go.
      struct SyncOnError {
        cudaStream_t s;
        int exceptions = std::uncaught_exceptions();
        ~SyncOnError() {
          if (std::uncaught_exceptions() > exceptions) cudaStreamSynchronize(s);
        }
      } syncOnError{s};
      float* dst[2] = {static_cast<float*>(inputs_->ptr), static_cast<float*>(inputs_->ptr) + n};
      check(cudaMemsetAsync(flag_->ptr, 0, sizeof(unsigned), s), "cudaMemsetAsync");
      for (int k = 0; k < 2; ++k) {
        StridedPixels src{};
        int type = 2;
        if (in[k].device) {
          const DeviceView& v = in[k].view;
          if (v.stream) check(ctx_->waitFor(streamFromInterface(v.stream)), "waiting for the input's stream");
          if (v.syncWithLegacy) check(ctx_->waitFor(cudaStreamLegacy), "waiting for the default stream");
          src = {reinterpret_cast<const unsigned char*>(v.data), v.strides[0], v.strides[1],
                 v.ndim == 3 ? v.strides[2] : 0, v.ndim == 3 ? int(v.shape[2]) : 1};
          type = int(v.type);
        } else {
          // Host input, already converted: upload, then the same kernel in place for the NaN test.
          check(cudaMemcpyAsync(dst[k], pinnedIn_ + size_t(k) * size_t(n), size_t(n) * sizeof(float),
                                cudaMemcpyHostToDevice, s),
                "upload");
          src = {reinterpret_cast<const unsigned char*>(dst[k]), (long long)width_ * 4, 4, 0, 1};
        }
        check(launchToGray(src, type, width_, height_, dst[k], static_cast<unsigned*>(flag_->ptr), 1u << k, s),
              "input conversion");
      }
      const cuda::DeviceDepth d = sequence ? stereo_->next(dst[0], dst[1], pose) : stereo_->compute(dst[0], dst[1]);
      result.warm = d.warm;
      fa.validIn = d.valid, fa.radial = d.radial, fa.z = d.z, fa.disparity = d.disparity, fa.warp = d.warp;
      fa.points = d.points, fa.confidence = d.confidence;
      // valid, radial, z, points, disparity, warp, confidence: PackArgs' outputs.
      const bool want[7] = {true, true, sel.points, sel.points, sel.disparity, sel.warp, true};
      const size_t bytes[7] = {1, 4, 4, 12, 4, 8, 4};
      void* out[7] = {};
      for (int i = 0; i < 7; ++i)
        if (want[i]) out[i] = buffer(size_t(n) * bytes[i]);
      if (!returnDevice) {
        reserveHostOutputs(hostBytes);
        for (int i = 0, k = 0; i < 7; ++i)
          if (want[i]) out[i] = static_cast<char*>(hostOutDevice_->ptr) + offsets[size_t(k++)];
      }
      fa.valid = static_cast<unsigned char*>(out[0]);
      fa.outRadial = static_cast<float*>(out[1]);
      fa.outZ = static_cast<float*>(out[2]);
      fa.outPoints = static_cast<float*>(out[3]);
      fa.outDisparity = static_cast<float*>(out[4]);
      fa.outWarp = static_cast<float*>(out[5]);
      fa.outConfidence = static_cast<float*>(out[6]);
      check(launchPackResult(fa, s), "result copy");
      if (!returnDevice)
        check(cudaMemcpyAsync(pinnedOut_, hostOutDevice_->ptr, hostBytes, cudaMemcpyDeviceToHost, s), "download");
      check(cudaMemcpyAsync(pinnedFlag_, flag_->ptr, sizeof flag, cudaMemcpyDeviceToHost, s), "flag download");
      check(cudaStreamSynchronize(s), "compute");
      flag = *pinnedFlag_;
    }
    // As the host API words it (stereo.cpp checkImage).
    if (flag & 1u) throw Error("left image contains NaN or infinite pixels");
    if (flag & 2u) throw Error("right image contains NaN or infinite pixels");

    size_t next = 0;
    const long long h = height_, w = width_;
    // Host results: one copy out of the pinned buffer into recycled storage (see ResultPool),
    // which the NumPy array then owns.
    auto hostArray = [&](std::vector<long long> shape, bool isBool) -> pb::object {
      const char* src = static_cast<const char*>(pinnedOut_) + offsets[next++];
      if (isBool) return boolArray(pooledCopy<unsigned char>(*pool, src, width_, height_), pool);
      switch (shape.size() == 3 ? shape[2] : 1) {
        case 1:
          return floatArray(pooledCopy<float>(*pool, src, width_, height_), pool);
        case 2:
          return flowArray(pooledCopy<Vec2f>(*pool, src, width_, height_), pool);
        default:
          return pointArray(pooledCopy<Point3f>(*pool, src, width_, height_), pool);
      }
    };
    auto take = [&](const void* p, std::vector<long long> shape, bool isBool) -> pb::object {
      if (!p) return pb::none();
      if (!returnDevice) return hostArray(std::move(shape), isBool);
      const std::shared_ptr<DeviceBuffer>& b = buffers[next++];
      return pb::cast(DeviceArray{b, std::move(shape), isBool});
    };
    result.valid = take(fa.valid, {h, w}, true);
    result.depth = take(fa.outRadial, {h, w}, false);
    result.z = take(fa.outZ, {h, w}, false);
    result.points = take(fa.outPoints, {h, w, 3}, false);
    result.disparity = take(fa.outDisparity, {h, w}, false);
    result.warp = take(fa.outWarp, {h, w, 2}, false);
    result.confidence = take(fa.outConfidence, {h, w}, false);
    // Nothing is read back to judge a frame by (DeviceStereo::next has no warm-failure check).
    result.redone = false;
    result.consistentShare = result.meanConfidence = std::numeric_limits<double>::quiet_NaN();
    result.lrPassShare = std::numeric_limits<double>::quiet_NaN();
    result.totalMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return result;
  }

 private:
  struct Input {
    bool device = false;
    DeviceView view;
  };

  // Device memory and pinned host memory for host results, kept and grown to fit.
  void reserveHostOutputs(size_t bytes) {
    if (hostOutDevice_ && hostOutDevice_->bytes >= bytes) return;
    hostOutDevice_.reset();
    if (pinnedOut_) {
      check(cudaStreamSynchronize(ctx_->stream), "compute");
      cudaFreeHost(pinnedOut_);
      pinnedOut_ = nullptr;
    }
    hostOutDevice_ = std::make_shared<DeviceBuffer>(ctx_, bytes);
    check(cudaMallocHost(&pinnedOut_, bytes), "cudaMallocHost");
  }

  Input input(pb::handle obj, const char* which, uintptr_t ours, int slot) {
    Input in;
    const auto sizeText = [](long long w, long long h) { return std::to_string(w) + "x" + std::to_string(h); };
    if (isDeviceArray(obj)) {
      in.device = true;
      in.view = deviceView(obj, which, ours);
      const DeviceView& v = in.view;
      if (v.shape[0] != height_ || v.shape[1] != width_)
        throw Error(std::string(which) + " is " + sizeText(v.shape[1], v.shape[0]) + " but the calibration says " +
                    sizeText(width_, height_));
      int device = v.device;
      if (device < 0) {  // __cuda_array_interface__ does not say: ask the driver
        cudaPointerAttributes attr{};
        if (cudaPointerGetAttributes(&attr, reinterpret_cast<const void*>(v.data)) != cudaSuccess ||
            (attr.type != cudaMemoryTypeDevice && attr.type != cudaMemoryTypeManaged)) {
          cudaGetLastError();
          throw Error(std::string(which) + " is not CUDA device memory");
        }
        device = attr.device;
      }
      if (device != ctx_->device)
        throw Error(std::string(which) + " is on CUDA device " + std::to_string(device) + " but this Stereo runs on " +
                    std::to_string(ctx_->device));
    } else {
      const HostImage host = hostImage(obj, which);
      if (host.width != width_ || host.height != height_)
        throw Error(std::string(which) + " is " + sizeText(host.width, host.height) + " but the calibration says " +
                    sizeText(width_, height_));
      const size_t n = size_t(width_) * size_t(height_);
      if (!pinnedIn_)
        check(cudaMallocHost(reinterpret_cast<void**>(&pinnedIn_), 2 * n * sizeof(float)), "cudaMallocHost");
      convertGray(host, pinnedIn_ + size_t(slot) * n);  // the last frame's upload is done: compute() synchronised
    }
    return in;
  }

  std::shared_ptr<CudaContext> ctx_;
  int width_, height_;
  std::unique_ptr<cuda::DeviceStereo> stereo_;  // after ctx_: destroyed before its stream
  std::shared_ptr<DeviceBuffer> inputs_, flag_;
  std::shared_ptr<DeviceBuffer> hostOutDevice_;  // host results before their download
  unsigned* pinnedFlag_ = nullptr;
  float* pinnedIn_ = nullptr;  // host inputs, converted: 2 x width x height floats
  void* pinnedOut_ = nullptr;  // host results, downloaded (hostOutDevice_'s layout)
};

void DevicePathDeleter::operator()(DevicePath* p) const { delete p; }

DevicePathPtr makeDevicePath(const Rig& rig, const Params& params, const std::string& backendSpec) {
  return DevicePathPtr(new DevicePath(rig, params, deviceIndex(backendSpec)));
}
void devicePathSetPose(DevicePath& d, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) { d.setPose(R, t); }
void devicePathSetMask(DevicePath& d, const ImageU8& mask) { d.setMask(mask); }
Result devicePathCompute(DevicePath& d, pb::handle left, pb::handle right, bool returnDevice,
                         const Stereo::Outputs& outputs, const std::shared_ptr<ResultPool>& pool) {
  return d.compute(left, right, returnDevice, outputs, pool);
}
Result devicePathNext(DevicePath& d, pb::handle left, pb::handle right, const Pose* pose, bool returnDevice,
                      const Stereo::Outputs& outputs, const std::shared_ptr<ResultPool>& pool) {
  return d.compute(left, right, returnDevice, outputs, pool, true, pose);
}
void devicePathResetSequence(DevicePath& d) { d.resetSequence(); }

void bindDevice(pb::module_& m) {
  pb::class_<DeviceArray>(m, "DeviceArray",
                          "A result on the GPU (compute(..., return_device=True)). CuPy and PyTorch wrap it without "
                          "a copy: cupy.asarray(a), cupy.from_dlpack(a), torch.from_dlpack(a), torch.as_tensor(a, "
                          "device='cuda'). It owns its memory; wrappers keep it alive.")
      .def_property_readonly("__cuda_array_interface__", &cudaArrayInterface)
      .def(
          "__dlpack__",
          [](const DeviceArray& a, pb::object, pb::object, pb::object, pb::object) { return exportDlpack(a); },
          pb::kw_only(), pb::arg("stream") = pb::none(), pb::arg("max_version") = pb::none(),
          pb::arg("dl_device") = pb::none(), pb::arg("copy") = pb::none(),
          "DLPack export (the data is ready: compute() synchronised, so any stream may read it).")
      .def("__dlpack_device__",
           [](const DeviceArray& a) { return pb::make_tuple(int(kDLCUDA), a.buffer->ctx->device); })
      .def_property_readonly("shape",
                             [](const DeviceArray& a) {
                               pb::tuple t(a.shape.size());
                               for (size_t i = 0; i < a.shape.size(); ++i) t[i] = pb::int_(a.shape[i]);
                               return t;
                             })
      .def_property_readonly(
          "dtype", [](const DeviceArray& a) { return a.isBool ? pb::dtype::of<bool>() : pb::dtype::of<float>(); })
      .def_property_readonly("ptr", [](const DeviceArray& a) { return reinterpret_cast<uintptr_t>(a.buffer->ptr); })
      .def_property_readonly("device_id", [](const DeviceArray& a) { return a.buffer->ctx->device; })
      .def("get", &toHost, "A NumPy copy on the host.")
      .def("__repr__", [](const DeviceArray& a) {
        std::string s;
        for (size_t i = 0; i < a.shape.size(); ++i) s += (i ? ", " : "") + std::to_string(a.shape[i]);
        return "<curvestereo.DeviceArray (" + s + ") " + (a.isBool ? "bool" : "float32") +
               " on cuda:" + std::to_string(a.buffer->ctx->device) + ">";
      });
}

}  // namespace cs::py

// Pieces of the Python module shared by its source files: array conversions, the table of
// solver parameters, and the device-array path (CUDA builds only).
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "curvestereo/image.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/pose.hpp"
#include "curvestereo/sequence.hpp"
#include "curvestereo/stereo.hpp"
#include "pixels.hpp"

namespace cs::py {

namespace pb = pybind11;

// ---------------------------------------------------------------- host arrays

// The pixel conversion behind imageFromArray, shared with the CUDA kernels' host mirror:
// one sample scaled to [0, 1] (uint8: /255, uint16: /65535, float32: as is).
enum class PixelType { U8, U16, F32 };
PixelType pixelTypeOf(char kind, int bits, const char* which);  // kind 'u' / 'f', else cs::Error

// A 2-D uint8 / uint16 / float32 array (gray) or H x W x 1|3|4 (colour, alpha dropped), any
// strides, checked and described (no pixel read yet). Throws cs::Error naming `which` on a
// bad dtype or shape.
struct HostImage {
  pb::array array;  // keeps the pixels alive
  PixelType type = PixelType::F32;
  StridedPixels pixels{};
  int width = 0, height = 0;
};
HostImage hostImage(pb::handle obj, const char* which);
// Its pixels as the library's float gray, packed (width * height floats at dst). Integer
// pixels are scaled and colour is converted exactly as the PNG reader does (Rec. 601 luma,
// so an array and the PNG it came from give bit-identical input).
void convertGray(const HostImage& h, float* dst);
// The same into a new image, or into `into`, whose storage is kept when its size matches
// (the per-frame inputs of a Stereo: no allocation and no page faults after the first).
ImageF imageFromArray(pb::handle obj, const char* which);
void imageFromArray(pb::handle obj, const char* which, ImageF& into);
// A gray uint8 array (H x W, or H x W x 1), any strides, copied as it is into `into` (kept
// storage as above): a camera's 8-bit frame, which Stereo takes as bytes. False for any
// other array (imageFromArray converts those).
bool bytesFromArray(const HostImage& h, ImageU8& into);
// Non-zero pixels of a 2-D array of any numeric or bool dtype, as a mask.
ImageU8 maskFromArray(pb::handle obj, const char* which);

// Recycled host storage for result arrays, one per Stereo. Each array handed to Python owns
// its storage (it stays valid after the next frame and after the Stereo is gone); when the
// array is dropped, its storage comes back here instead of being freed, and the next frame
// computes into it. A fresh multi-MB buffer costs a zero fill and a page fault per 4 KiB
// page on first touch, which is slow under some sandboxes (gVisor); a recycled one costs
// neither. In a loop `r = stereo.compute(...)` two frames' buffers circulate.
class ResultPool {
 public:
  // Which outputs a frame had (the next frame is lent buffers for those).
  struct Present {
    bool valid = false, radial = false, z = false, points = false, disparity = false, warp = false, confidence = false;
  };
  // Moves recycled storage into r's images for the outputs the last frame had (the
  // library's compute() keeps storage of the right size).
  void lend(DepthResult& r);
  void remember(const Present& p, size_t pixels) {
    std::lock_guard<std::mutex> lock(mutex_);
    last_ = p, lastSize_ = pixels;
  }
  // n elements: recycled storage if there is some (contents: an old frame's), else new.
  template <class T>
  std::vector<T> take(size_t n);
  // Called by an array's capsule when the array is dropped (any thread, GIL held).
  template <class T>
  void giveBack(std::vector<T>&& v);

 private:
  template <class T>
  std::vector<std::vector<T>>& shelfOf();
  static constexpr size_t kShelfSize = 8;  // per element type: a few frames' worth, no more
  std::mutex mutex_;
  std::vector<std::vector<float>> floats_;
  std::vector<std::vector<unsigned char>> bytes_;
  std::vector<std::vector<Vec2f>> flows_;
  std::vector<std::vector<Point3f>> points_;
  Present last_;
  size_t lastSize_ = 0;
};

// Arrays that own the moved storage of the library's images (no copy of the pixels); with a
// pool, the storage goes back to it when the array is dropped.
pb::array floatArray(ImageF&& img, const std::shared_ptr<ResultPool>& pool = nullptr);
pb::array boolArray(ImageU8&& img, const std::shared_ptr<ResultPool>& pool = nullptr);
pb::array flowArray(FlowImage&& img, const std::shared_ptr<ResultPool>& pool = nullptr);
pb::array pointArray(Image<Point3f>&& img, const std::shared_ptr<ResultPool>& pool = nullptr);

// The Python-side result: NumPy arrays (host) or DeviceArray objects (CUDA), None for
// outputs not computed.
struct Result {
  pb::object depth, z, points, disparity, warp, valid, confidence;
  pb::dict stages;
  double totalMs = 0;
  // Sequences (Stereo.next): DepthResult's warm, redone, consistentShare and meanConfidence.
  bool warm = false, redone = false;
  double consistentShare = 0, meanConfidence = 0;
  double lrPassShare = 0;  // DepthResult's (lr_check)
};
Result resultFromDepth(DepthResult&& r, const std::shared_ptr<ResultPool>& pool = nullptr);

// ---------------------------------------------------------------- device arrays

// What an object's __cuda_array_interface__ or __dlpack__ describes (parsed with the GIL
// held; no CUDA call). Strides are in bytes.
struct DeviceView {
  uintptr_t data = 0;
  int ndim = 0;
  long long shape[3] = {0, 0, 0};
  long long strides[3] = {0, 0, 0};
  PixelType type = PixelType::F32;
  int device = 0;
  // Stream the producer wrote on (__cuda_array_interface__ v3 "stream"): 0 none given,
  // 1 legacy default, 2 per-thread default, else a cudaStream_t. DLPack producers are
  // handed our stream instead, so they order their work before it themselves.
  uintptr_t stream = 0;
  bool syncWithLegacy = false;  // no stream given: assume the default stream's work must finish
  pb::object keepAlive;         // the exporting object or the DLPack capsule
};
// True for objects exposing __cuda_array_interface__, or __dlpack__ on a CUDA device.
bool isDeviceArray(pb::handle obj);
// consumerStream: our stream's handle for __dlpack__(stream=...).
DeviceView deviceView(pb::handle obj, const char* which, uintptr_t consumerStream);

// ---------------------------------------------------------------- parameters

// The preset with keyword overrides applied (snake_case Params names, CLI aliases);
// unknown keys and bad values raise cs::Error naming the key. Validated.
Params paramsFrom(const std::string& preset, const pb::dict& overrides);
// Every parameter by its Python name.
pb::dict paramsToDict(const Params& p);
std::vector<std::string> paramNames();

// ---------------------------------------------------------------- the module's parts

void bindDevice(pb::module_& m);    // DeviceArray (an empty stub without CUDA)
void bindSequence(pb::module_& m);  // Sequence and Frame (sequence.cpp)
void bindRigs(pb::module_& m);      // CameraRig, RigStereo, RigResult, Panorama (rig.cpp)

// {'model', 'width', 'height', 'params'}: a camera as Rig.cam0 and CameraRig.cameras show it.
pb::dict cameraDict(const Camera& c);

// A frame's pose for Stereo.next (T_world_cam0): None (nullopt), a 4 x 4 array, or an
// (R, t) pair. Throws cs::Error naming the accepted forms on anything else.
std::optional<Pose> poseFrom(pb::handle obj);
// T_world_cam0 as a 4 x 4 float64 array.
pb::array poseArray(const Pose& pose);
// A Sequence's or RigSequence's options from their Python arguments (poses: None or a path).
SequenceOptions sequenceOptions(pb::object poses, double pairToleranceMs, double poseToleranceMs);
// Python's index i (negative from the end) into a sequence of n frames; IndexError outside.
size_t frameIndex(long long i, size_t n);

#ifdef CS_PY_CUDA
// The CUDA device path of one Stereo (created on first use): device or host inputs,
// device or host outputs; see device.cpp.
class DevicePath;
struct DevicePathDeleter {
  void operator()(DevicePath* p) const;
};
using DevicePathPtr = std::unique_ptr<DevicePath, DevicePathDeleter>;
DevicePathPtr makeDevicePath(const Rig& rig, const Params& params, const std::string& backendSpec);
void devicePathSetPose(DevicePath& d, const Eigen::Matrix3d& R, const Eigen::Vector3d& t);
void devicePathSetMask(DevicePath& d, const ImageU8& mask);
// Host outputs (returnDevice false) are NumPy arrays over `pool`'s recycled storage.
Result devicePathCompute(DevicePath& d, pb::handle left, pb::handle right, bool returnDevice,
                         const Stereo::Outputs& outputs, const std::shared_ptr<ResultPool>& pool);
// DeviceStereo::next: as devicePathCompute, one frame of the device path's sequence.
Result devicePathNext(DevicePath& d, pb::handle left, pb::handle right, const Pose* pose, bool returnDevice,
                      const Stereo::Outputs& outputs, const std::shared_ptr<ResultPool>& pool);
void devicePathResetSequence(DevicePath& d);
#endif

}  // namespace cs::py

// The `curvestereo` Python module: calibration, the solver, image and point-cloud I/O.
// NumPy in and out; every library failure surfaces as curvestereo.Error with the
// library's one-line message. Docstrings here are what help() shows; the signatures with
// types are in curvestereo/__init__.pyi.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <optional>

#include "binding.hpp"
#include "curvestereo/backends.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/rig.hpp"

namespace cs::py {

pb::dict cameraDict(const Camera& c) {
  pb::dict d;
  d["model"] = c.modelName();
  d["width"] = c.width;
  d["height"] = c.height;
  d["params"] = c.params;
  return d;
}

namespace {

// ---------------------------------------------------------------- calibration

// Paths arrive as std::filesystem::path: str and os.PathLike (pathlib) both convert.
using Path = std::filesystem::path;

// Every format the library reads (docs/calibration.md), chosen from the keys.
Rig loadRig(const Path& path) { return loadCalibration(path.string()); }

void saveRig(const Rig& rig, const Path& path, const std::string& format) {
  for (CalibFormat f :
       {CalibFormat::Kalibr, CalibFormat::Basalt, CalibFormat::OpenCv, CalibFormat::OrbSlam3, CalibFormat::VinsFusion})
    if (format == calibFormatName(f)) return saveCalibration(rig, path.string(), f);
  throw Error("unknown calibration format '" + format + "' (known: kalibr, basalt, opencv, orbslam3, vins)");
}

pb::array matrixArray(const double* data, std::vector<pb::ssize_t> shape) {
  pb::array_t<double> a(shape);
  std::copy(data, data + a.size(), a.mutable_data());
  return std::move(a);
}

Eigen::Matrix3d rotationFrom(pb::handle obj) {
  const auto a = pb::array_t<double, pb::array::c_style | pb::array::forcecast>::ensure(obj);
  if (!a || a.ndim() != 2 || a.shape(0) != 3 || a.shape(1) != 3) throw Error("R must be a 3 x 3 array");
  Eigen::Matrix3d R;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = a.at(r, c);
  return R;
}

Eigen::Vector3d vectorFrom(pb::handle obj) {
  const auto a = pb::array_t<double, pb::array::c_style | pb::array::forcecast>::ensure(obj);
  if (!a || a.size() != 3 || a.ndim() > 2) throw Error("t must hold 3 values");
  return {a.data()[0], a.data()[1], a.data()[2]};
}

// ---------------------------------------------------------------- images

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

pb::array readImage(const Path& file) {
  const std::string path = file.string();
  const std::string ext = lowerExtension(path);
  if (ext == ".exr") {
    ImageF img = readExr(path);
    return floatArray(std::move(img));
  }
  if (ext == ".flo") {
    FlowImage flow = readFlo(path);
    return flowArray(std::move(flow));
  }
  ImageF img;
  {
    pb::gil_scoped_release nogil;  // large PNGs take a while to inflate
    img = readPngGray(path);
  }
  return floatArray(std::move(img));
}

void writePng(const Path& file, pb::handle obj, int bits) {
  const std::string path = file.string();
  const pb::array a = pb::array::ensure(obj);
  if (!a) throw Error("write_png: expected an array");
  if (bits != 8 && bits != 16) throw Error("write_png: bits must be 8 or 16");
  const char kind = a.dtype().kind();
  if (a.ndim() == 3 && a.shape(2) == 3) {
    // Colour pictures (depth_picture(), colorize()): 8-bit RGB through the library's writer.
    if (kind != 'u' || a.itemsize() != 1) throw Error("write_png: an H x W x 3 picture must be uint8");
    const auto rgb = pb::array_t<uint8_t, pb::array::c_style>::ensure(a);
    Image<uint32_t> img(int(a.shape(1)), int(a.shape(0)));
    for (size_t i = 0; i < img.size(); ++i)
      img.data[i] = uint32_t(rgb.data()[3 * i]) << 16 | uint32_t(rgb.data()[3 * i + 1]) << 8 | rgb.data()[3 * i + 2];
    writePngRgb(path, img);
    return;
  }
  if (a.ndim() != 2) throw Error("write_png: expected H x W (gray) or H x W x 3 (uint8 RGB)");
  // Gray: the same scaling as the readers, so write then read gives the pixels back.
  ImageF img = imageFromArray(a, "write_png image");
  if (kind == 'u' && a.itemsize() == 2) bits = 16;
  if (bits == 16)
    writePngGray16(path, img);
  else
    writePngGray(path, img);
}

void writeExrFile(const Path& file, pb::handle obj) {
  const std::string path = file.string();
  const pb::array a = pb::array::ensure(obj);
  if (!a || a.ndim() != 2 || a.dtype().kind() != 'f' || a.itemsize() != 4)
    throw Error("write_exr: expected an H x W float32 array");
  writeExr(path, imageFromArray(a, "write_exr image"));
}

pb::array rgbArray(const Image<uint32_t>& img) {
  pb::array_t<uint8_t> out({pb::ssize_t(img.height), pb::ssize_t(img.width), pb::ssize_t(3)});
  uint8_t* o = out.mutable_data();
  for (size_t i = 0; i < img.size(); ++i) {
    o[3 * i] = uint8_t(img.data[i] >> 16), o[3 * i + 1] = uint8_t(img.data[i] >> 8),
          o[3 * i + 2] = uint8_t(img.data[i]);
  }
  return std::move(out);
}

ImageF floatImage2d(pb::handle obj, const char* what) {
  const pb::array a = pb::array::ensure(obj);
  if (!a || a.ndim() != 2 || a.dtype().kind() != 'f')
    throw Error(std::string(what) + ": expected an H x W float array");
  const auto f = pb::array_t<float, pb::array::c_style | pb::array::forcecast>::ensure(a);
  ImageF img(int(a.shape(1)), int(a.shape(0)));
  std::copy(f.data(), f.data() + img.size(), img.data.begin());
  return img;
}

// Binary PLY of the finite points (as `curvestereo run` writes them). Gray colours go
// through the library's writer; RGB needs a vertex layout it does not have, so those are
// written here in the same format (x y z float, red green blue uchar).
void writePlyFile(const Path& file, pb::handle pointsObj, pb::handle coloursObj) {
  const std::string path = file.string();
  const auto pts = pb::array_t<float, pb::array::c_style | pb::array::forcecast>::ensure(pointsObj);
  if (!pts || pts.ndim() < 1 || pts.shape(pts.ndim() - 1) != 3)
    throw Error("write_ply: points must be an array of shape (..., 3)");
  const size_t n = size_t(pts.size() / 3);
  int colourChannels = 0;
  pb::array_t<float, pb::array::c_style | pb::array::forcecast> col;
  bool colourBytes = false;
  if (!coloursObj.is_none()) {
    const pb::array raw = pb::array::ensure(coloursObj);
    if (!raw) throw Error("write_ply: colours must be an array");
    colourBytes = raw.dtype().kind() == 'u' && raw.itemsize() == 1;
    col = pb::array_t<float, pb::array::c_style | pb::array::forcecast>::ensure(raw);
    if (size_t(col.size()) == n)
      colourChannels = 1;
    else if (size_t(col.size()) == 3 * n && col.shape(col.ndim() - 1) == 3)
      colourChannels = 3;
    else
      throw Error("write_ply: colours must have the points' shape without the last axis (gray) or with 3 (RGB)");
  }
  // uint8 colours as they are; float colours in [0, 1], as the CLI scales the left image.
  auto byteOf = [&](float v) {
    if (colourBytes) return uint8_t(v);
    return uint8_t(std::lround(255.f * std::min(1.f, std::max(0.f, v))));
  };
  const float* p = pts.data();
  auto finite = [&](size_t i) {
    return std::isfinite(p[3 * i]) && std::isfinite(p[3 * i + 1]) && std::isfinite(p[3 * i + 2]);
  };
  if (colourChannels != 3) {
    std::vector<PlyPoint> out;
    for (size_t i = 0; i < n; ++i)
      if (finite(i))
        out.push_back({p[3 * i], p[3 * i + 1], p[3 * i + 2], colourChannels ? byteOf(col.data()[i]) : uint8_t(255)});
    writePly(path, out);
    return;
  }
  std::vector<char> body;
  size_t count = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!finite(i)) continue;
    const char* xyz = reinterpret_cast<const char*>(p + 3 * i);  // little-endian hosts only, as the library
    body.insert(body.end(), xyz, xyz + 12);
    for (int c = 0; c < 3; ++c) body.push_back(char(byteOf(col.data()[3 * i + size_t(c)])));
    ++count;
  }
  const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(count) +
                             "\nproperty float x\nproperty float y\nproperty float z\n"
                             "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw Error("cannot write point cloud '" + path + "': " + std::strerror(errno));
  const bool ok = std::fwrite(header.data(), 1, header.size(), f) == header.size() &&
                  std::fwrite(body.data(), 1, body.size(), f) == body.size();
  if (std::fclose(f) != 0 || !ok) throw Error("cannot write point cloud '" + path + "': " + std::strerror(errno));
}

std::vector<std::string> backendList(bool usable) {
  std::vector<std::string> names;
  for (const std::string& name : availableBackends()) {
    if (!usable || backendAvailable(name)) names.push_back(name);
  }
  return names;
}

// ---------------------------------------------------------------- the solver

Stereo::Outputs parseOutputs(pb::handle obj) {
  Stereo::Outputs o{false, false, false};
  if (obj.is_none()) return {true, true, true};
  if (pb::isinstance<pb::str>(obj)) throw Error("outputs must be a list of names, e.g. ['points']");
  for (pb::handle item : obj) {
    const std::string name = pb::str(item);
    if (name == "disparity")
      o.disparity = true;
    else if (name == "warp")
      o.warp = true;
    else if (name == "points" || name == "z")
      o.points = true;
    else if (name != "depth" && name != "valid")
      throw Error("unknown output '" + name + "' (known: depth, valid, disparity, warp, points, z)");
  }
  return o;
}

// Raised from the progress callback to stop a CPU frame early (see compute()).
struct ProgressAbort {};

class PyStereo {
 public:
  PyStereo(const Rig& rig, const std::string& presetName, const std::string& backend, pb::kwargs kwargs)
      : backendSpec_(backend) {
    pb::dict overrides;
    pb::object outputs = pb::none(), profile = pb::none();
    for (auto item : kwargs) {
      const std::string key = pb::str(item.first);
      if (key == "outputs")
        outputs = pb::reinterpret_borrow<pb::object>(item.second);
      else if (key == "profile")
        profile = pb::reinterpret_borrow<pb::object>(item.second);
      else if (key == "device")  // the CLI's --device: an index or a name substring
        backendSpec_ += ":" + std::string(pb::str(item.second));
      else
        overrides[item.first] = item.second;
    }
    params_ = paramsFrom(presetName, overrides);
    outputs_ = parseOutputs(outputs);
    {
      pb::gil_scoped_release nogil;  // setting up a GPU backend takes a while
      stereo_ = std::make_unique<Stereo>(rig, params_, backendSpec_);
    }
    stereo_->setOutputs(outputs_);
    // Stage timing synchronises at every stage and stops GPU frame replay: on by default
    // only where it costs nothing (the CPU backend).
    stereo_->setProfiling(profile.is_none() ? stereo_->backendName() == "cpu" : profile.cast<bool>());
  }

  Result compute(pb::handle left, pb::handle right, pb::object progress, bool returnDevice) {
    auto lock = claim();
    return solve(left, right, progress, returnDevice, Kind::Single, nullptr);
  }

  // Stereo::next: one frame of a sequence (pose: T_world_cam0, see poseFrom).
  Result next(pb::handle left, pb::handle right, pb::handle poseObj, pb::object progress, bool returnDevice) {
    const std::optional<Pose> pose = poseFrom(poseObj);
    auto lock = claim();
    return solve(left, right, progress, returnDevice, Kind::Sequence, pose ? &*pose : nullptr);
  }

  void resetSequence() {
    auto lock = claim();
    stereo_->resetSequence();
#ifdef CS_PY_CUDA
    if (device_) devicePathResetSequence(*device_);
#endif
    sequencePath_ = SequenceOn::None;
  }

  void setPose(pb::handle Robj, pb::handle tobj) {
    const Eigen::Matrix3d R = rotationFrom(Robj);
    const Eigen::Vector3d t = vectorFrom(tobj);
    auto lock = claim();
    pb::gil_scoped_release nogil;
    stereo_->setPose(R, t);
#ifdef CS_PY_CUDA
    if (device_) devicePathSetPose(*device_, R, t);
#endif
  }

  void setMask(pb::handle obj) {
    ImageU8 mask = maskFromArray(obj, "mask");
    auto lock = claim();
    pb::gil_scoped_release nogil;
    stereo_->setMask(mask);
#ifdef CS_PY_CUDA
    if (device_) devicePathSetMask(*device_, mask);
#endif
    mask_ = std::move(mask);
  }

  const Stereo& stereo() const { return *stereo_; }
  const Params& params() const { return params_; }
  Stereo::Outputs outputs() const { return outputs_; }

 private:
  enum class Kind { Single, Sequence };
  // Which pipeline the sequence's frames went through: the host Stereo and the device path
  // each carry their own previous frame.
  enum class SequenceOn { None, Host, Device };

  // compute() and next(), with the claim held.
  Result solve(pb::handle left, pb::handle right, pb::object progress, bool returnDevice, Kind kind, const Pose* pose) {
    if (returnDevice || isDeviceArray(left) || isDeviceArray(right))
      return computeOnDevice(left, right, returnDevice, kind, pose);
    // Into this object's input images (claimed above): no allocation after the first frame.
    // A camera's 8-bit frames go to the library as they are (a quarter of the bytes).
    const HostImage leftHost = hostImage(left, "left image"), rightHost = hostImage(right, "right image");
    const bool bytes = bytesFromArray(leftHost, leftBytes_) && bytesFromArray(rightHost, rightBytes_);
    if (!bytes) {
      imageFromArray(left, "left image", left_);
      imageFromArray(right, "right image", right_);
    }
    if (kind == Kind::Sequence) enterSequencePath(SequenceOn::Host);
    if (!progress.is_none() && !PyCallable_Check(progress.ptr())) throw Error("progress must be callable");
    // The callback runs on this thread with the GIL taken back. If it raises, the exception
    // is re-raised from compute(); on the CPU backend the frame also stops at once (GPU
    // frames are recorded as a whole and short: they finish first).
    std::optional<pb::error_already_set> raised;
    const bool abortable = stereo_->backendName() == "cpu";
    if (!progress.is_none())
      stereo_->setProgress([&](double fraction) {
        if (raised) return;
        pb::gil_scoped_acquire gil;
        try {
          progress(fraction);
        } catch (pb::error_already_set& e) {
          raised.emplace(std::move(e));
          if (abortable) throw ProgressAbort{};
        }
      });
    struct Reset {
      Stereo& s;
      ~Reset() { s.setProgress(nullptr); }
    } reset{*stereo_};
    // The library computes into recycled storage (what earlier results' arrays gave back when
    // they were dropped), and the arrays below take it over without a copy.
    DepthResult out;
    pool_->lend(out);
    {
      pb::gil_scoped_release nogil;
      try {
        if (kind == Kind::Sequence && bytes)
          stereo_->next(leftBytes_, rightBytes_, out, pose);
        else if (kind == Kind::Sequence)
          stereo_->next(left_, right_, out, pose);
        else if (bytes)
          stereo_->compute(leftBytes_, rightBytes_, out);
        else
          stereo_->compute(left_, right_, out);
      } catch (const ProgressAbort&) {
      }
    }
    if (raised) {
      pb::error_already_set e = std::move(*raised);
      raised.reset();
      throw e;
    }
    return resultFromDepth(std::move(out), pool_);
  }

  // A sequence that moves from one pipeline to the other (host arrays, then GPU arrays)
  // must not warm-start from the stale frame the other one last saw: it starts cold there.
  void enterSequencePath(SequenceOn path) {
    if (sequencePath_ != path && sequencePath_ != SequenceOn::None) {
      if (path == SequenceOn::Host) stereo_->resetSequence();
#ifdef CS_PY_CUDA
      if (path == SequenceOn::Device && device_) devicePathResetSequence(*device_);
#endif
    }
    sequencePath_ = path;
  }

  // One Stereo is not thread-safe, and compute() runs without the GIL: a second thread
  // using the same object gets an error instead of corrupting it.
  std::unique_lock<std::mutex> claim() {
    std::unique_lock<std::mutex> lock(busy_, std::try_to_lock);
    if (!lock.owns_lock()) throw Error("this Stereo object is in use by another thread (use one Stereo per thread)");
    return lock;
  }

  Result computeOnDevice(pb::handle left, pb::handle right, bool returnDevice, Kind kind, const Pose* pose) {
#ifdef CS_PY_CUDA
    if (stereo_->backendName() != "cuda")
      throw Error("GPU arrays and return_device need the CUDA backend; this Stereo runs on " + stereo_->backendName() +
                  " (Stereo(..., backend='cuda'))");
    if (!device_) {
      // The device-pointer API is a second pipeline on the same GPU, set up on first use.
      pb::gil_scoped_release nogil;
      device_ = makeDevicePath(stereo_->rig(), params_, backendSpec_);
      if (!mask_.empty()) devicePathSetMask(*device_, mask_);
    }
    if (kind == Kind::Sequence) {
      enterSequencePath(SequenceOn::Device);
      return devicePathNext(*device_, left, right, pose, returnDevice, outputs_, pool_);
    }
    return devicePathCompute(*device_, left, right, returnDevice, outputs_, pool_);
#else
    (void)left, (void)right, (void)returnDevice, (void)kind, (void)pose;
    throw Error(
        "GPU arrays and return_device need the CUDA backend, which this build does not have (build with nvcc "
        "installed)");
#endif
  }

  std::mutex busy_;
  std::string backendSpec_;
  Params params_;
  Stereo::Outputs outputs_;
  std::unique_ptr<Stereo> stereo_;
  ImageU8 mask_;
  ImageF left_, right_;             // the last frame's converted inputs, reused (compute() holds the claim)
  ImageU8 leftBytes_, rightBytes_;  // the same for 8-bit gray frames
  SequenceOn sequencePath_ = SequenceOn::None;
  std::shared_ptr<ResultPool> pool_ = std::make_shared<ResultPool>();
#ifdef CS_PY_CUDA
  DevicePathPtr device_;
#endif
};

std::string sizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

}  // namespace

#ifndef CS_PY_CUDA
void bindDevice(pb::module_&) {}
#endif

}  // namespace cs::py

using namespace cs;
using namespace cs::py;

namespace {

// pybind11 before 2.12 reads NumPy's dtype descriptor in NumPy 1's layout: under NumPy 2
// every item size reads 0, so images would be refused with a nonsense dtype ("uint0") or
// misread. Seen when an older pybind11's headers shadow the interpreter's own (CPATH).
void requireNumpyThisPybindReads() {
#if PYBIND11_VERSION_MAJOR < 2 || (PYBIND11_VERSION_MAJOR == 2 && PYBIND11_VERSION_MINOR < 12)
  const std::string version = pb::str(pb::module_::import("numpy").attr("__version__"));
  if (std::atoi(version.c_str()) >= 2)
    throw pb::import_error(
        "curvestereo was built with pybind11 " PYBIND11_TOSTRING(PYBIND11_VERSION_MAJOR) "." PYBIND11_TOSTRING(
            PYBIND11_VERSION_MINOR) ", which cannot read NumPy " +
        version + " arrays: rebuild it with pybind11 >= 2.12");
#endif
}

}  // namespace

PYBIND11_MODULE(_curvestereo, m) {
  requireNumpyThisPybindReads();
  m.doc() = "Dense depth from a calibrated fisheye stereo pair, over the whole field of view (curvestereo).";
  pb::register_exception<Error>(m, "Error", PyExc_RuntimeError);
  m.attr("__version__") = CS_PY_VERSION;

  pb::class_<Rig>(m, "Rig", "A calibrated stereo rig: two cameras and the pose of camera 1 (X1 = R X0 + t).")
      .def_property_readonly(
          "width", [](const Rig& r) { return r.cam0.width; }, "Image width in pixels.")
      .def_property_readonly(
          "height", [](const Rig& r) { return r.cam0.height; }, "Image height in pixels.")
      .def_property_readonly(
          "R",
          [](const Rig& r) {
            return matrixArray(r.R.transpose().data(), {3, 3});
          },
          "Rotation of camera 1 relative to camera 0 (3 x 3, float64).")
      .def_property_readonly(
          "t", [](const Rig& r) { return matrixArray(r.t.data(), {3}); },
          "Translation of camera 1 relative to camera 0 (metres, float64).")
      .def_property_readonly(
          "baseline", [](const Rig& r) { return r.t.norm(); }, "|t| in metres.")
      .def_property_readonly(
          "cam0", [](const Rig& r) { return cameraDict(r.cam0); },
          "Camera 0 (left): {'model', 'width', 'height', 'params': [fx, fy, cx, cy, ...]}.")
      .def_property_readonly(
          "cam1", [](const Rig& r) { return cameraDict(r.cam1); }, "Camera 1 (right), as cam0.")
      .def(
          "scaled",
          [](const Rig& r, double s) {
            Rig out = r;
            out.cam0 = r.cam0.scaled(s);
            out.cam1 = r.cam1.scaled(s);
            out.validate();
            return out;
          },
          pb::arg("factor"),
          "The same rig for images rescaled by `factor` (e.g. 0.5 for a half-resolution T265 stream).")
      .def("save", &saveRig, pb::arg("path"), pb::arg("format") = "kalibr",
           "Write the rig: format 'kalibr' (camchain.yaml), 'basalt' (calibration.json) or 'opencv' (FileStorage "
           "YAML, or XML when the path ends in .xml).")
      .def("__repr__", [](const Rig& r) {
        return "<curvestereo.Rig " + sizeText(r.cam0.width, r.cam0.height) + " " + r.cam0.modelName() + ", baseline " +
               std::to_string(r.t.norm()) + " m>";
      });

  m.def("load_calibration", &loadRig, pb::arg("path"),
        "Read a stereo calibration as a Rig: Kalibr camchain.yaml, Basalt calibration.json or OpenCV FileStorage "
        "(YAML / XML), the format told from the content. Raises curvestereo.Error naming the file and the problem.");

  pb::class_<Result>(m, "Result",
                     "One frame's output. Arrays are NumPy (host) or curvestereo.DeviceArray "
                     "(compute(..., return_device=True)); invalid pixels are NaN in every float output.")
      .def_property_readonly(
          "depth", [](const Result& r) { return r.depth; },
          "Radial depth (distance from camera 0's centre), metres, float32 H x W; NaN where "
          "invalid, +inf at infinity.")
      .def_property_readonly(
          "z", [](const Result& r) { return r.z; },
          "Depth along camera 0's optical axis (None "
          "without the points output).")
      .def_property_readonly(
          "points", [](const Result& r) { return r.points; },
          "3-D points in camera-0 coordinates, float32 H x W x 3 (NaN where invalid or infinite).")
      .def_property_readonly(
          "disparity", [](const Result& r) { return r.disparity; },
          "Disparity along the epipolar curve, px, float32 H x W.")
      .def_property_readonly(
          "warp", [](const Result& r) { return r.warp; },
          "2-D displacement into the calibrated right image, px, float32 H x W x 2.")
      .def_property_readonly(
          "valid", [](const Result& r) { return r.valid; }, "bool H x W: pixels that were solved.")
      .def_property_readonly(
          "confidence", [](const Result& r) { return r.confidence; },
          "How far each pixel's depth can be trusted, in [0, 1] (float32 H x W; NaN where not valid): "
          "the structure along the epipolar curve, the photometric agreement, the sweep's and (with "
          "lr_check) the round trip's consistency. None only when left out by outputs.")
      .def_property_readonly(
          "stages", [](const Result& r) { return r.stages; },
          "Milliseconds per stage of this frame ({} when profiling is off).")
      .def_property_readonly(
          "total_ms", [](const Result& r) { return r.totalMs; }, "Wall time of compute() or next(), ms.")
      .def_property_readonly(
          "warm", [](const Result& r) { return r.warm; },
          "next(): whether the frame started from the previous frame's estimate (False for a cold frame and "
          "from compute()).")
      .def_property_readonly(
          "redone", [](const Result& r) { return r.redone; },
          "next(): whether a warm frame failed its check (warm_fail_ratio) and was solved again cold.")
      .def_property_readonly(
          "consistent_share", [](const Result& r) { return r.consistentShare; },
          "next(): share of the valid pixels at the sweep's level that passed its left-right check, in [0, 1] (what "
          "a warm frame is judged by); NaN from compute(), without the initialiser and on the GPU-array path.")
      .def_property_readonly(
          "mean_confidence", [](const Result& r) { return r.meanConfidence; },
          "next(): mean confidence over the field of view, in [0, 1]: it falls where the images disagree with the "
          "estimate (the other figure a warm frame is judged by); NaN from compute(), with warm_fail_ratio 0 and on "
          "the GPU-array path.")
      .def_property_readonly(
          "lr_pass_share", [](const Result& r) { return r.lrPassShare; },
          "lr_check: share of the pixels in the field of view whose left-right round trip passed, in [0, 1] (the "
          "figure a real pair has without ground truth); NaN without lr_check and on the GPU-array path.")
      .def("__repr__", [](const Result& r) {
        const std::string shape = pb::str(r.depth.attr("shape"));
        return "<curvestereo.Result " + shape + ", " + std::to_string(r.totalMs) + " ms>";
      });

  pb::class_<PyStereo>(m, "Stereo", R"doc(The solver for one rig: set up once, then compute() per frame
(or next() per frame of a sequence).

Stereo(rig, preset="realtime", backend="auto", *, outputs=None, profile=None, **overrides)

preset: one of presets(). backend: "auto", "cpu", "cuda", "vulkan", optionally with a
device ("vulkan:1", "cuda:0"; or device=1 / device="RTX", as the CLI's --device). overrides: solver parameters by name (warps=20,
lambda_=3.0, du_max=0.3, init="planesweep", ...; see Stereo.params for all). outputs: the
optional outputs to compute, a subset of ["disparity", "warp", "points"] (depth and valid
always; fewer means less to transfer from a GPU). profile: fill Result.stages (default: on
for the CPU backend only, as it synchronises GPU backends at every stage).
One Stereo must not be used by two threads at once (it raises if it is); use one per thread.)doc")
      .def(pb::init<const Rig&, const std::string&, const std::string&, pb::kwargs>(), pb::arg("rig"),
           pb::arg("preset") = "realtime", pb::arg("backend") = "auto")
      .def("compute", &PyStereo::compute, pb::arg("left"), pb::arg("right"), pb::kw_only(),
           pb::arg("progress") = pb::none(), pb::arg("return_device") = false,
           R"doc(Solve one pair and return a Result.

left, right: H x W uint8 / uint16 / float32 arrays (gray, any strides) or H x W x 3 colour
(R, G, B; converted to Rec. 601 luma as the PNG reader does), of the rig's size. uint8 and
uint16 are scaled to [0, 1]; gray uint8 frames go to the backend as bytes (a quarter of the
transfer, the same result). With the CUDA backend they may also be GPU arrays (CuPy,
PyTorch: __dlpack__ or __cuda_array_interface__), read in place. return_device=True leaves
the results on the GPU as DeviceArray objects. progress: called with the fraction done
(0..1) on this thread; an exception it raises is re-raised here (on the CPU backend it
also stops the frame). GPU frames replay a recorded graph and report little in between;
the GPU-array path (device inputs or return_device) reports nothing and leaves stages
empty. The GIL is released while the frame is solved.)doc")
      .def("next", &PyStereo::next, pb::arg("left"), pb::arg("right"), pb::arg("pose") = pb::none(), pb::kw_only(),
           pb::arg("progress") = pb::none(), pb::arg("return_device") = false,
           R"doc(Solve the next frame of a sequence and return a Result (images as in compute()).

From the second frame on it starts from the previous frame's estimate carried into this
frame's view (warm_start, with the band sweep of preset "realtime") and filters the
result over time (temporal_strength). pose: camera 0's pose for this frame, T_world_cam0
(a point X in camera 0's frame is R X + t in the world): None, a 4 x 4 array, or an
(R, t) pair (3 x 3, 3); with the previous frame's pose the carried estimate follows the
rig's motion, without it is carried as it is. Every cold_every-th frame is solved cold,
and a warm frame whose consistent share falls below warm_fail_ratio x the last cold
frame's is solved again cold. Result.warm / .redone / .consistent_share tell which.
GPU arrays and return_device use the CUDA device path, which has no warm-failure check
(redone is always False there). A sequence that switches between host and GPU arrays
starts cold on the side it switches to. compute() in between does not disturb the
sequence.)doc")
      .def("reset_sequence", &PyStereo::resetSequence,
           "Start a new sequence: the next next() is solved cold and nothing is carried into it.")
      .def("set_pose", &PyStereo::setPose, pb::arg("R"), pb::arg("t"),
           "For a moving camera: the pose of the second view relative to the first (X1 = R X0 + t).")
      .def("set_mask", &PyStereo::setMask, pb::arg("mask"),
           "Restrict the solve to mask != 0 (an H x W array, e.g. the lens's image circle).")
      .def_property_readonly(
          "backend", [](const PyStereo& s) { return s.stereo().backendName(); },
          "The backend in use: 'cpu', 'cuda' or 'vulkan'.")
      .def_property_readonly(
          "device", [](const PyStereo& s) { return s.stereo().deviceName(); }, "The device it runs on, in words.")
      .def_property_readonly(
          "backend_choice", [](const PyStereo& s) { return s.stereo().backendChoice(); },
          "Which backend 'auto' took, and why.")
      .def_property_readonly(
          "buffer_bytes", [](const PyStereo& s) { return s.stereo().bufferBytes(); },
          "Bytes of the frame's buffers on the backend (the levels' images, the sweep's volumes).")
      .def_property_readonly(
          "rig", [](const PyStereo& s) { return s.stereo().rig(); }, "The rig, with the pose of the latest set_pose().")
      .def_property_readonly(
          "params", [](const PyStereo& s) { return paramsToDict(s.params()); },
          "Every solver parameter in use, by the names Stereo() takes.")
      .def_property_readonly(
          "outputs",
          [](const PyStereo& s) {
            const Stereo::Outputs o = s.outputs();
            std::vector<std::string> names;
            if (o.disparity) names.push_back("disparity");
            if (o.warp) names.push_back("warp");
            if (o.points) names.push_back("points");
            return names;
          },
          "The optional outputs computed.")
      .def("__repr__", [](const PyStereo& s) {
        return "<curvestereo.Stereo " + sizeText(s.stereo().rig().cam0.width, s.stereo().rig().cam0.height) + " on " +
               s.stereo().backendName() + " (" + s.stereo().deviceName() + ")>";
      });

  m.def("read_image", &readImage, pb::arg("path"),
        "Read an image as float32: PNG (8/16-bit, gray or colour -> Rec. 601 luma, scaled to [0, 1], exactly as "
        "`curvestereo run` reads it), EXR (single channel), Middlebury .flo (H x W x 2).");
  m.def("write_png", &writePng, pb::arg("path"), pb::arg("image"), pb::arg("bits") = 8,
        "Write a PNG: H x W float32 in [0, 1] (8-bit, or 16 with bits=16), uint8, uint16 (16-bit), or H x W x 3 "
        "uint8 RGB (e.g. depth_picture()).");
  m.def("write_exr", &writeExrFile, pb::arg("path"), pb::arg("image"),
        "Write an H x W float32 array as a single-channel EXR (as `curvestereo run` writes depth.exr).");
  m.def(
      "write_ply", [](const Path& path, pb::handle points, pb::handle colours) { writePlyFile(path, points, colours); },
      pb::arg("path"), pb::arg("points"), pb::arg("colours") = pb::none(),
      "Write the finite points of an (..., 3) array as a binary PLY. colours: None (white), gray with the "
      "points' shape without the last axis (uint8, or float in [0, 1] such as the left image), or RGB (..., 3).");
  m.def(
      "depth_picture", [](pb::handle depth) { return rgbArray(depthPicture(floatImage2d(depth, "depth_picture"))); },
      pb::arg("depth"),
      "Radial depth as an H x W x 3 uint8 picture, the same as `curvestereo run`'s depth.png: inverse depth, "
      "colour-mapped between its 2nd and 98th percentile, invalid black.");
  m.def(
      "colorize",
      [](pb::handle values, float lo, float hi) {
        return rgbArray(colorizeScalar(floatImage2d(values, "colorize"), lo, hi));
      },
      pb::arg("values"), pb::arg("lo"), pb::arg("hi"),
      "An H x W float array as an H x W x 3 uint8 picture (the library's colour map from lo to hi; non-finite black).");
  m.def("presets", &presetNames, "Names of the parameter presets.");
  m.def(
      "preset_params", [](const std::string& name) { return paramsToDict(preset(name)); }, pb::arg("name"),
      "A preset's parameters, by the names Stereo() takes as overrides.");
  m.def("available_backends", &backendList, pb::arg("usable") = false,
        "Backends compiled into this build, in the order 'auto' tries them; with usable=True only those that "
        "can run on this machine (a device is present).");
  m.def(
      "build_info",
      [] {
        pb::dict d;
        d["version"] = CS_PY_VERSION;
        d["backends"] = availableBackends();
#ifdef CS_PY_CUDA
        d["cuda_arrays"] = true;
#else
        d["cuda_arrays"] = false;
#endif
        d["parameters"] = paramNames();
        return d;
      },
      "What this build contains: version, backends, whether GPU arrays are accepted, parameter names.");
  bindDevice(m);
  bindSequence(m);
  bindRigs(m);
}

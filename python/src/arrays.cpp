// NumPy <-> library images, and parsing of the GPU array protocols.
#include <algorithm>
#include <cstring>

#include "binding.hpp"
#include "dlpack.hpp"
#include "pixels.hpp"

namespace cs::py {

namespace {

std::string shapeText(const pb::array& a) {
  std::string s = "(";
  for (pb::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

pb::array asArray(pb::handle obj, const char* which) {
  if (obj.is_none()) throw Error(std::string(which) + " is None: expected an image array");
  // Anything NumPy can view (arrays, memoryviews, CPU tensors, nested lists), without
  // copying arrays.
  pb::array a = pb::array::ensure(obj);
  // An arbitrary object becomes a 0-d object array, a string a 0-d str array: say what it was.
  const bool converted = !pb::isinstance<pb::array>(obj);
  if (!a || (converted && (a.dtype().kind() == 'O' || a.dtype().kind() == 'U' || a.dtype().kind() == 'S')))
    throw Error(std::string(which) + " is a " + std::string(pb::str(obj.get_type().attr("__name__"))) +
                ", not an array");
  return a;
}

}  // namespace

PixelType pixelTypeOf(char kind, int bits, const char* which) {
  if (kind == 'u' && bits == 8) return PixelType::U8;
  if (kind == 'u' && bits == 16) return PixelType::U16;
  if (kind == 'f' && bits == 32) return PixelType::F32;
  const std::string name = kind == 'f'   ? "float" + std::to_string(bits)
                           : kind == 'u' ? "uint" + std::to_string(bits)
                           : kind == 'i' ? "int" + std::to_string(bits)
                           : kind == 'b' ? "bool"
                           : kind == 'c' ? "complex" + std::to_string(bits)
                                         : std::string("kind '") + kind + "'";
  throw Error(std::string(which) + " has dtype " + name +
              ": expected uint8, uint16 or float32 (convert with .astype(numpy.float32))");
}

ImageF imageFromArray(pb::handle obj, const char* which) {
  const pb::array a = asArray(obj, which);
  const int ndim = int(a.ndim());
  const int channels = ndim == 3 ? int(a.shape(2)) : 1;
  if (!(ndim == 2 || (ndim == 3 && (channels == 1 || channels == 3 || channels == 4))))
    throw Error(std::string(which) + " has shape " + shapeText(a) +
                ": expected H x W (gray) or H x W x 3 (colour, R G B)");
  const pb::dtype dt = a.dtype();
  const PixelType type = pixelTypeOf(dt.kind(), int(dt.itemsize()) * 8, which);
  const long long h = a.shape(0), w = a.shape(1);
  if (h > kMaxArraySide || w > kMaxArraySide)
    throw Error(std::string(which) + " has shape " + shapeText(a) + ": larger than the library handles");
  ImageF img{int(w), int(h)};
  const StridedPixels src{static_cast<const unsigned char*>(a.data()), a.strides(0), a.strides(1),
                          ndim == 3 ? a.strides(2) : 0, channels};
  // Plain loops over the caller's strides (a view, a crop, a flipped BGR image): the
  // conversion costs far less than one frame, and no intermediate copy is made.
  for (long long y = 0; y < h; ++y)
    for (long long x = 0; x < w; ++x) img.data[size_t(y * w + x)] = grayAt(src, int(type), y, x);
  return img;
}

ImageU8 maskFromArray(pb::handle obj, const char* which) {
  pb::array a = asArray(obj, which);
  if (a.ndim() != 2) throw Error(std::string(which) + " has shape " + shapeText(a) + ": expected H x W");
  const char kind = a.dtype().kind();
  if (kind != 'b' && kind != 'u' && kind != 'i' && kind != 'f')
    throw Error(std::string(which) + " must be a numeric or bool array");
  // Non-zero means "use": compare in the array's own type through NumPy.
  const pb::array nz = pb::array::ensure(a.attr("__ne__")(0).attr("astype")("uint8"), pb::array::c_style);
  ImageU8 mask(int(a.shape(1)), int(a.shape(0)));
  std::memcpy(mask.data.data(), nz.data(), mask.size());
  return mask;
}

// ---------------------------------------------------------------- results

namespace {

template <class T>
pb::array ownedArray(std::vector<T>&& data, const pb::dtype& dtype, std::vector<pb::ssize_t> shape) {
  auto* heap = new std::vector<T>(std::move(data));
  pb::capsule owner(heap, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return pb::array(dtype, std::move(shape), {}, heap->data(), owner);
}

pb::object orNone(pb::array&& a, bool present) { return present ? pb::object(std::move(a)) : pb::none(); }

}  // namespace

pb::array floatArray(ImageF&& img) {
  const pb::ssize_t h = img.height, w = img.width;
  return ownedArray(std::move(img.data), pb::dtype::of<float>(), {h, w});
}

pb::array boolArray(ImageU8&& img) {
  // The library's 0 / 1 bytes are NumPy bools as they are.
  const pb::ssize_t h = img.height, w = img.width;
  return ownedArray(std::move(img.data), pb::dtype::of<bool>(), {h, w});
}

pb::array flowArray(FlowImage&& img) {
  static_assert(sizeof(Vec2f) == 2 * sizeof(float), "Vec2f is two floats");
  const pb::ssize_t h = img.height, w = img.width;
  auto* heap = new std::vector<Vec2f>(std::move(img.data));
  pb::capsule owner(heap, [](void* p) { delete static_cast<std::vector<Vec2f>*>(p); });
  return pb::array(pb::dtype::of<float>(), {h, w, pb::ssize_t(2)}, {}, reinterpret_cast<const float*>(heap->data()),
                   owner);
}

pb::array pointArray(Image<Point3f>&& img) {
  static_assert(sizeof(Point3f) == 3 * sizeof(float), "Point3f is three floats");
  const pb::ssize_t h = img.height, w = img.width;
  auto* heap = new std::vector<Point3f>(std::move(img.data));
  pb::capsule owner(heap, [](void* p) { delete static_cast<std::vector<Point3f>*>(p); });
  return pb::array(pb::dtype::of<float>(), {h, w, pb::ssize_t(3)}, {}, reinterpret_cast<const float*>(heap->data()),
                   owner);
}

Result resultFromDepth(DepthResult&& r) {
  Result out;
  const bool hasZ = !r.depth.z.empty(), hasPoints = !r.depth.points.empty();
  const bool hasDisparity = !r.disparity.empty(), hasWarp = !r.warp.empty(), hasConf = !r.confidence.empty();
  out.depth = floatArray(std::move(r.depth.radial));
  out.valid = boolArray(std::move(r.valid));
  out.z = orNone(floatArray(std::move(r.depth.z)), hasZ);
  out.points = orNone(pointArray(std::move(r.depth.points)), hasPoints);
  out.disparity = orNone(floatArray(std::move(r.disparity)), hasDisparity);
  out.warp = orNone(flowArray(std::move(r.warp)), hasWarp);
  out.confidence = orNone(floatArray(std::move(r.confidence)), hasConf);
  for (const StageTime& s : r.stages) out.stages[pb::str(s.name)] = s.ms;
  out.totalMs = r.totalMs;
  return out;
}

// ---------------------------------------------------------------- device arrays

bool isDeviceArray(pb::handle obj) {
  if (pb::isinstance<pb::array>(obj)) return false;  // NumPy arrays have __dlpack__ too (on the CPU)
  if (pb::hasattr(obj, "__cuda_array_interface__")) return true;
  if (!pb::hasattr(obj, "__dlpack__") || !pb::hasattr(obj, "__dlpack_device__")) return false;
  const pb::tuple dev = obj.attr("__dlpack_device__")();
  return dev.size() >= 1 && dev[0].cast<int>() == kDLCUDA;
}

namespace {

DeviceView fromCudaArrayInterface(pb::handle obj, const char* which) {
  const std::string what = std::string(which) + " (__cuda_array_interface__)";
  const pb::object cai = obj.attr("__cuda_array_interface__");
  if (!pb::isinstance<pb::dict>(cai)) throw Error(what + " is not a dict");
  const pb::dict d = cai;
  for (const char* key : {"shape", "typestr", "data"})
    if (!d.contains(key)) throw Error(what + " has no '" + key + "'");
  if (d.contains("mask") && !d["mask"].is_none()) throw Error(what + " has a mask: masked arrays are not supported");
  DeviceView v;
  const std::string typestr = d["typestr"].cast<std::string>();
  if (typestr.size() < 3 || (typestr[0] == '>' && typestr != ">u1"))
    throw Error(what + " has typestr '" + typestr + "': expected little-endian uint8, uint16 or float32");
  v.type = pixelTypeOf(typestr[1], 8 * std::stoi(typestr.substr(2)), which);
  const pb::tuple shape = d["shape"];
  v.ndim = int(shape.size());
  if (v.ndim < 1 || v.ndim > 3) throw Error(what + " has " + std::to_string(v.ndim) + " dimensions");
  const long long item = v.type == PixelType::U8 ? 1 : v.type == PixelType::U16 ? 2 : 4;
  for (int i = 0; i < v.ndim; ++i) v.shape[i] = shape[size_t(i)].cast<long long>();
  const bool packed = !d.contains("strides") || d["strides"].is_none();
  if (packed) {
    long long s = item;
    for (int i = v.ndim; i-- > 0;) v.strides[i] = s, s *= v.shape[i];
  } else {
    const pb::tuple strides = d["strides"];
    if (int(strides.size()) != v.ndim) throw Error(what + " has strides of the wrong length");
    for (int i = 0; i < v.ndim; ++i) v.strides[i] = strides[size_t(i)].cast<long long>();
  }
  const pb::tuple data = d["data"];
  v.data = data[0].cast<uintptr_t>();
  // CAI v3: "stream" names where the data is being written; absent (v2 producers such as
  // PyTorch's) promises nothing, so we wait for the legacy default stream to be safe.
  if (d.contains("stream") && !d["stream"].is_none())
    v.stream = d["stream"].cast<uintptr_t>();
  else
    v.syncWithLegacy = true;
  // The device is the pointer's; DeviceStereo checks it matches (cudaPointerGetAttributes).
  v.device = -1;
  v.keepAlive = pb::reinterpret_borrow<pb::object>(obj);
  return v;
}

DeviceView fromDlpack(pb::handle obj, const char* which, uintptr_t consumerStream) {
  const std::string what = std::string(which) + " (__dlpack__)";
  const pb::object capsule = obj.attr("__dlpack__")(pb::arg("stream") = consumerStream);
  if (!PyCapsule_IsValid(capsule.ptr(), "dltensor")) throw Error(what + " did not return a DLPack capsule");
  auto* managed = static_cast<DLManagedTensor*>(PyCapsule_GetPointer(capsule.ptr(), "dltensor"));
  const DLTensor& t = managed->dl_tensor;
  if (t.device.device_type != kDLCUDA) throw Error(what + " is not on a CUDA device");
  if (t.dtype.lanes != 1) throw Error(what + " has vector lanes");
  const char kind = t.dtype.code == kDLUInt ? 'u' : t.dtype.code == kDLFloat ? 'f' : t.dtype.code == kDLInt ? 'i' : 'b';
  DeviceView v;
  v.type = pixelTypeOf(kind, t.dtype.bits, which);
  v.ndim = t.ndim;
  if (v.ndim < 1 || v.ndim > 3) throw Error(what + " has " + std::to_string(v.ndim) + " dimensions");
  const long long item = t.dtype.bits / 8;
  long long s = item;
  for (int i = v.ndim; i-- > 0;) {
    v.shape[i] = t.shape[i];
    v.strides[i] = t.strides ? t.strides[i] * item : s;  // DLPack strides count elements
    s *= v.shape[i];
  }
  v.data = reinterpret_cast<uintptr_t>(t.data) + t.byte_offset;
  v.device = t.device.device_id;
  // Left unconsumed: the capsule's own destructor releases the tensor when we drop it.
  v.keepAlive = capsule;
  return v;
}

}  // namespace

DeviceView deviceView(pb::handle obj, const char* which, uintptr_t consumerStream) {
  DeviceView v;
  // DLPack first: its producer orders its pending work before our stream itself, which
  // __cuda_array_interface__ (v2, PyTorch) cannot. Producers refuse some views (negative
  // strides, read-only): those go through __cuda_array_interface__ when there is one.
  const bool cai = pb::hasattr(obj, "__cuda_array_interface__");
  if (pb::hasattr(obj, "__dlpack__") && pb::hasattr(obj, "__dlpack_device__") &&
      pb::tuple(obj.attr("__dlpack_device__")())[0].cast<int>() == kDLCUDA) {
    try {
      v = fromDlpack(obj, which, consumerStream);
    } catch (pb::error_already_set&) {
      if (!cai) throw;
      v = fromCudaArrayInterface(obj, which);
    }
  } else {
    v = fromCudaArrayInterface(obj, which);
  }
  const int channels = v.ndim == 3 ? int(v.shape[2]) : 1;
  if (!(v.ndim == 2 || (v.ndim == 3 && (channels == 1 || channels == 3 || channels == 4)))) {
    std::string s = "(";
    for (int i = 0; i < v.ndim; ++i) s += (i ? ", " : "") + std::to_string(v.shape[i]);
    throw Error(std::string(which) + " has shape " + s + (v.ndim == 1 ? ",)" : ")") +
                ": expected H x W (gray) or H x W x 3 (colour, R G B)");
  }
  if (v.shape[0] > kMaxArraySide || v.shape[1] > kMaxArraySide)
    throw Error(std::string(which) + " is larger than the library handles");
  return v;
}

}  // namespace cs::py

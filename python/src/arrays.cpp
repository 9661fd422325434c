// NumPy <-> library images, and parsing of the GPU array protocols.
#include <algorithm>
#include <cstring>
#include <type_traits>

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

HostImage hostImage(pb::handle obj, const char* which) {
  HostImage h;
  h.array = asArray(obj, which);
  const pb::array& a = h.array;
  const int ndim = int(a.ndim());
  const int channels = ndim == 3 ? int(a.shape(2)) : 1;
  if (!(ndim == 2 || (ndim == 3 && (channels == 1 || channels == 3 || channels == 4))))
    throw Error(std::string(which) + " has shape " + shapeText(a) +
                ": expected H x W (gray) or H x W x 3 (colour, R G B)");
  const pb::dtype dt = a.dtype();
  h.type = pixelTypeOf(dt.kind(), int(dt.itemsize()) * 8, which);
  if (a.shape(0) > kMaxArraySide || a.shape(1) > kMaxArraySide)
    throw Error(std::string(which) + " has shape " + shapeText(a) + ": larger than the library handles");
  h.width = int(a.shape(1));
  h.height = int(a.shape(0));
  h.pixels = {static_cast<const unsigned char*>(a.data()), a.strides(0), a.strides(1), ndim == 3 ? a.strides(2) : 0,
              channels};
  return h;
}

namespace {

// sampleAt for every 8- and 16-bit value, so a pixel costs a load instead of a division in
// double (the same function fills them: the same bits).
const float* sampleTable(PixelType type) {
  static const std::vector<float> u8 = [] {
    std::vector<float> t(256);
    for (unsigned v = 0; v < 256; ++v) {
      const unsigned char b = static_cast<unsigned char>(v);
      t[v] = sampleAt(&b, 0);
    }
    return t;
  }();
  if (type == PixelType::U8) return u8.data();
  static const std::vector<float> u16 = [] {
    std::vector<float> t(65536);
    for (unsigned v = 0; v < 65536; ++v) {
      const unsigned short s = static_cast<unsigned short>(v);
      t[v] = sampleAt(reinterpret_cast<const unsigned char*>(&s), 1);
    }
    return t;
  }();
  return u16.data();
}

// One row of gray pixels: a table look-up (integers) or the float itself.
template <PixelType T>
inline float sampleOf(const unsigned char* p, const float* table) {
  if constexpr (T == PixelType::U8) {
    return table[*p];
  } else if constexpr (T == PixelType::U16) {
    unsigned short v;
    std::memcpy(&v, p, sizeof v);
    return table[v];
  } else {
    float v;
    std::memcpy(&v, p, sizeof v);
    return v;
  }
}

template <PixelType T>
void convertRows(const StridedPixels& s, int width, int height, float* dst) {
  const float* table = T == PixelType::F32 ? nullptr : sampleTable(T);
  constexpr long long item = T == PixelType::U8 ? 1 : T == PixelType::U16 ? 2 : 4;
  for (long long y = 0; y < height; ++y) {
    const unsigned char* row = s.data + y * s.rowStride;
    float* out = dst + y * width;
    if (s.channels < 3) {
      if (T == PixelType::F32 && s.colStride == item) {
        std::memcpy(out, row, size_t(width) * sizeof(float));  // packed float gray rows
      } else {
        for (long long x = 0; x < width; ++x) out[x] = sampleOf<T>(row + x * s.colStride, table);
      }
      continue;
    }
    // Colour: grayAt's luma, with the samples from the tables.
    for (long long x = 0; x < width; ++x) {
      const unsigned char* p = row + x * s.colStride;
      out[x] =
          lumaOf(sampleOf<T>(p, table), sampleOf<T>(p + s.chanStride, table), sampleOf<T>(p + 2 * s.chanStride, table));
    }
  }
}

}  // namespace

void convertGray(const HostImage& h, float* dst) {
  // Over the caller's strides (a view, a crop, a flipped BGR image), no intermediate copy.
  switch (h.type) {
    case PixelType::U8:
      return convertRows<PixelType::U8>(h.pixels, h.width, h.height, dst);
    case PixelType::U16:
      return convertRows<PixelType::U16>(h.pixels, h.width, h.height, dst);
    case PixelType::F32:
      return convertRows<PixelType::F32>(h.pixels, h.width, h.height, dst);
  }
}

ImageF imageFromArray(pb::handle obj, const char* which) {
  ImageF img;
  imageFromArray(obj, which, img);
  return img;
}

void imageFromArray(pb::handle obj, const char* which, ImageF& into) {
  const HostImage h = hostImage(obj, which);
  into.width = h.width;
  into.height = h.height;
  into.data.resize(size_t(h.width) * size_t(h.height));  // keeps the storage of the last frame's
  convertGray(h, into.data.data());
}

bool bytesFromArray(const HostImage& h, ImageU8& into) {
  if (h.type != PixelType::U8 || h.pixels.channels != 1) return false;
  into.width = h.width;
  into.height = h.height;
  into.data.resize(size_t(h.width) * size_t(h.height));
  const bool packedRows = h.pixels.colStride == 1;
  for (int y = 0; y < h.height; ++y) {
    const unsigned char* row = h.pixels.data + y * h.pixels.rowStride;
    uint8_t* out = into.data.data() + size_t(y) * size_t(h.width);
    if (packedRows) {
      std::memcpy(out, row, size_t(h.width));
      continue;
    }
    for (int x = 0; x < h.width; ++x) out[x] = row[x * h.pixels.colStride];
  }
  return true;
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

// The storage of one result array: a capsule owns it as the array's base. Dropped, it goes
// back to the pool it came from (if that still exists and has room), else it is freed.
template <class T>
struct PooledStorage {
  std::vector<T> data;
  std::weak_ptr<ResultPool> home;
};

template <class T>
std::vector<T> ResultPool::take(size_t n) {
  std::vector<T> v;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto& shelf = shelfOf<T>();
    if (!shelf.empty()) {
      v = std::move(shelf.back());
      shelf.pop_back();
    }
  }
  v.resize(n);  // no-op for a recycled buffer of this size (the usual case): no zero fill, no page faults
  return v;
}

template <class T>
void ResultPool::giveBack(std::vector<T>&& v) {
  if (v.empty()) return;
  std::lock_guard<std::mutex> lock(mutex_);
  auto& shelf = shelfOf<T>();
  if (shelf.size() < kShelfSize) shelf.push_back(std::move(v));
}

template <class T>
std::vector<std::vector<T>>& ResultPool::shelfOf() {
  if constexpr (std::is_same_v<T, float>)
    return floats_;
  else if constexpr (std::is_same_v<T, unsigned char>)
    return bytes_;
  else if constexpr (std::is_same_v<T, Vec2f>)
    return flows_;
  else
    return points_;
}

void ResultPool::lend(DepthResult& r) {
  // Only the outputs the last frame had: an output not computed would free what it is lent.
  const size_t n = lastSize_;
  if (n == 0) return;
  if (last_.valid) r.valid.data = take<unsigned char>(n);
  if (last_.radial) r.depth.radial.data = take<float>(n);
  if (last_.z) r.depth.z.data = take<float>(n);
  if (last_.points) r.depth.points.data = take<Point3f>(n);
  if (last_.disparity) r.disparity.data = take<float>(n);
  if (last_.warp) r.warp.data = take<Vec2f>(n);
  if (last_.confidence) r.confidence.data = take<float>(n);
}

namespace {

// An array over pooled storage (pool may be null: plain owned storage). `Scalar` is the
// element type NumPy sees; `extra` the trailing axis of multi-channel pixels (0: none).
template <class T, class Scalar>
pb::array pooledArray(std::vector<T>&& data, const std::shared_ptr<ResultPool>& pool, pb::ssize_t h, pb::ssize_t w,
                      pb::ssize_t extra) {
  auto* owned = new PooledStorage<T>{std::move(data), pool};
  pb::capsule base(owned, [](void* p) {
    auto* s = static_cast<PooledStorage<T>*>(p);
    if (auto home = s->home.lock()) home->giveBack(std::move(s->data));
    delete s;
  });
  std::vector<pb::ssize_t> shape{h, w};
  if (extra) shape.push_back(extra);
  return pb::array(pb::dtype::of<Scalar>(), std::move(shape), {}, reinterpret_cast<const Scalar*>(owned->data.data()),
                   base);
}

pb::object orNone(pb::array&& a, bool present) { return present ? pb::object(std::move(a)) : pb::none(); }

}  // namespace

static_assert(sizeof(Vec2f) == 2 * sizeof(float), "Vec2f is two floats");
static_assert(sizeof(Point3f) == 3 * sizeof(float), "Point3f is three floats");

pb::array floatArray(ImageF&& img, const std::shared_ptr<ResultPool>& pool) {
  return pooledArray<float, float>(std::move(img.data), pool, img.height, img.width, 0);
}

pb::array boolArray(ImageU8&& img, const std::shared_ptr<ResultPool>& pool) {
  // The library's 0 / 1 bytes are NumPy bools as they are.
  return pooledArray<unsigned char, bool>(std::move(img.data), pool, img.height, img.width, 0);
}

pb::array flowArray(FlowImage&& img, const std::shared_ptr<ResultPool>& pool) {
  return pooledArray<Vec2f, float>(std::move(img.data), pool, img.height, img.width, 2);
}

pb::array pointArray(Image<Point3f>&& img, const std::shared_ptr<ResultPool>& pool) {
  return pooledArray<Point3f, float>(std::move(img.data), pool, img.height, img.width, 3);
}

Result resultFromDepth(DepthResult&& r, const std::shared_ptr<ResultPool>& pool) {
  Result out;
  ResultPool::Present has;
  has.valid = !r.valid.empty();
  has.radial = !r.depth.radial.empty();
  has.z = !r.depth.z.empty();
  has.points = !r.depth.points.empty();
  has.disparity = !r.disparity.empty();
  has.warp = !r.warp.empty();
  has.confidence = !r.confidence.empty();
  if (pool) pool->remember(has, r.depth.radial.size());
  // The images' storage moves into the arrays: no copy.
  out.depth = floatArray(std::move(r.depth.radial), pool);
  out.valid = boolArray(std::move(r.valid), pool);
  out.z = orNone(floatArray(std::move(r.depth.z), pool), has.z);
  out.points = orNone(pointArray(std::move(r.depth.points), pool), has.points);
  out.disparity = orNone(floatArray(std::move(r.disparity), pool), has.disparity);
  out.warp = orNone(flowArray(std::move(r.warp), pool), has.warp);
  out.confidence = orNone(floatArray(std::move(r.confidence), pool), has.confidence);
  for (const StageTime& s : r.stages) out.stages[pb::str(s.name)] = s.ms;
  out.totalMs = r.totalMs;
  out.warm = r.warm, out.redone = r.redone, out.consistentShare = r.consistentShare;
  out.meanConfidence = r.meanConfidence;
  out.lrPassShare = r.lrPassShare;
  return out;
}

template std::vector<float> ResultPool::take<float>(size_t);
template std::vector<unsigned char> ResultPool::take<unsigned char>(size_t);
template std::vector<Vec2f> ResultPool::take<Vec2f>(size_t);
template std::vector<Point3f> ResultPool::take<Point3f>(size_t);

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

// The kernel interface's helpers (gaussianTaps, the CameraParams conversions)
// and Backend's default stage clock (host wall time between boundaries).
#include "curvestereo/backend.hpp"

#include "curvestereo/camera.hpp"
#include "curvestereo/camera_models.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/parallel.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>

namespace cs {

namespace {

double nowMs() {
  using namespace std::chrono;
  return duration<double, std::milli>(steady_clock::now().time_since_epoch()).count();
}

// What the model's constructor precomputes (CameraParams::constants).
CameraConstants cameraConstants(const CameraParams& c) {
  if (models::paramCount(CameraModel(c.model)) < 0) throw Error("unknown camera model " + std::to_string(c.model));
  const auto model = models::makeModel<double>(CameraModel(c.model), c.params, c.width, c.height);
  const std::array<double, 2> k = std::visit([](const auto& m) { return m.precomputed(); }, model);
  return CameraConstants{k[0], k[1]};
}

}  // namespace

// A table instead of a division a pixel: the same values, an eighth of the time.
void floatsFromBytes(float* dst, const uint8_t* src, size_t n) {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int v = 0; v < 256; ++v) t[size_t(v)] = unitFromByte(uint8_t(v));
    return t;
  }();
  for (size_t i = 0; i < n; ++i) dst[i] = table[src[i]];
}

// A memcpy on one thread moves a few GB/s, below the memory's bandwidth (on the H200's host,
// 0.08-0.09 ms for each 0.7 MB image of a warm frame). In pieces of 256 KiB across the pool,
// large enough that waking the workers costs little beside each piece.
constexpr size_t kCopyPieceBytes = size_t(1) << 18;

void copyBytes(void* dst, const void* src, size_t bytes) {
  detail::parallelPieces(bytes, kCopyPieceBytes, [&](size_t begin, size_t end) {
    std::memcpy(static_cast<char*>(dst) + begin, static_cast<const char*>(src) + begin, end - begin);
  });
}

// Branch-free, so the compiler vectorises it: v - v is 0 for a finite v and NaN for NaN or
// +-inf, which compares unequal to 0. (A float sum of v - v would not vectorise: without
// -ffast-math the additions must stay in order.)
static bool copyFiniteFloats(float* dst, const float* src, size_t n) {
  int bad = 0;
  for (size_t i = 0; i < n; ++i) {
    const float v = src[i];
    dst[i] = v;
    bad |= !(v - v == 0.f);
  }
  return !bad;
}

void copyFloats(float* dst, const float* src, size_t n, bool* finite) {
  if (!finite) return copyBytes(dst, src, n * sizeof(float));
  std::atomic<bool> allFinite{true};
  detail::parallelPieces(n, kCopyPieceBytes / sizeof(float), [&](size_t begin, size_t end) {
    if (!copyFiniteFloats(dst + begin, src + begin, end - begin)) allFinite = false;
  });
  *finite = allFinite;
}

std::vector<float> gaussianTaps(float sigma) {
  const int radius = int(std::ceil(3.f * sigma));
  std::vector<float> taps(size_t(2 * radius + 1));
  float sum = 0.f;
  for (int i = -radius; i <= radius; ++i)
    sum += taps[size_t(i + radius)] = std::exp(-float(i * i) / (2.f * sigma * sigma));
  for (float& t : taps) t /= sum;
  return taps;
}

static_assert(models::Mei<double>::kNumParams <= kMaxCameraParams, "the kernels' camera blocks are too small");

CameraParams toCameraParams(const Camera& camera) {
  CameraParams p;
  p.model = int(camera.model);
  p.width = camera.width;
  p.height = camera.height;
  if (camera.params.size() > size_t(kMaxCameraParams)) throw Error("camera has more parameters than kernels take");
  std::copy(camera.params.begin(), camera.params.end(), p.params);
  p.constants = cameraConstants(p);
  return p;
}

Camera toCamera(const CameraParams& p) {
  Camera c;
  c.model = CameraModel(p.model);
  c.width = p.width;
  c.height = p.height;
  c.params.assign(p.params, p.params + std::max(0, models::paramCount(c.model)));
  return c;
}

void Backend::beginStage(const std::string& name) {
  synchronize();
  const double t = nowMs();
  if (!currentStage_.empty()) {
    auto it = std::find_if(stages_.begin(), stages_.end(), [&](const StageTime& s) { return s.name == currentStage_; });
    if (it == stages_.end())
      stages_.push_back({currentStage_, t - stageStartMs_});
    else
      it->ms += t - stageStartMs_;
  }
  currentStage_ = name;
  stageStartMs_ = t;
}

std::vector<StageTime> Backend::takeStageTimes() {
  beginStage("");
  currentStage_.clear();
  std::vector<StageTime> out;
  out.swap(stages_);
  return out;
}

}  // namespace cs

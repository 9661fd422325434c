#include "cpu_backend.hpp"

#include <algorithm>
#include <thread>

#include "curvestereo/image.hpp"

namespace cs::cpu {

void parallelRows(int height, const std::function<void(int)>& body) {
  int threads = int(std::max(1u, std::thread::hardware_concurrency()));
  threads = std::min(threads, std::max(1, height / 16));
  if (threads <= 1) {
    for (int y = 0; y < height; ++y) body(y);
    return;
  }
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      for (int y = t; y < height; y += threads) body(y);
    });
  for (auto& th : pool) th.join();
}

std::string CpuBackend::device() const {
  return "CPU, " + std::to_string(std::max(1u, std::thread::hardware_concurrency())) + " threads (scalar reference)";
}

Buffer CpuBackend::create(int width, int height, int channels) {
  if (width <= 0 || height <= 0 || channels <= 0) throw Error("cpu backend: invalid buffer size");
  Buffer b{int(storage_.size()), width, height, channels};
  storage_.emplace_back(b.count(), 0.f);
  return b;
}

View CpuBackend::view(const Buffer& b) {
  if (b.id < 0 || size_t(b.id) >= storage_.size()) throw Error("cpu backend: unknown buffer");
  return View{storage_[size_t(b.id)].data(), b.width, b.height, b.channels};
}

void CpuBackend::upload(const Buffer& dst, const float* host) {
  std::copy(host, host + dst.count(), view(dst).data);
}

void CpuBackend::download(const Buffer& src, float* host) {
  const float* d = view(src).data;
  std::copy(d, d + src.count(), host);
}

void CpuBackend::fill(const Buffer& dst, float value) { std::fill_n(view(dst).data, dst.count(), value); }

void CpuBackend::copy(const Buffer& dst, const Buffer& src) {
  if (dst.count() != src.count()) throw Error("cpu backend: copy between buffers of different size");
  const float* s = view(src).data;
  std::copy(s, s + src.count(), view(dst).data);
}

void CpuBackend::warp(const Buffer& dst, const Buffer& src, const Buffer& flow) {
  cpu::warp(view(dst), view(src), view(flow));
}

void CpuBackend::downsample(const Buffer& dst, const Buffer& src, float scale) {
  cpu::downsample(view(dst), view(src), scale);
}

void CpuBackend::upsample(const Buffer& dst, const Buffer& src, float scale, float valueScale) {
  cpu::upsample(view(dst), view(src), scale, valueScale);
}

void CpuBackend::structureTensor(const Buffer& tensor, const Buffer& steps, const Buffer& image,
                                 const Buffer& mask, const TensorParams& params) {
  cpu::structureTensor(view(tensor), view(steps), view(image), view(mask), params);
}

void CpuBackend::warpDerivatives(const DataTermBuffers& data, const Buffer& tangent, const Buffer& i0,
                                 const Buffer& i1, const Buffer& trajectory, const Buffer& w, const Buffer& u,
                                 const Buffer& mask) {
  cpu::warpDerivatives(view(data.u0), view(data.iu), view(data.iz), view(tangent), view(i0), view(i1),
                       view(trajectory), view(w), view(u), view(mask));
}

void CpuBackend::primalDual(const PrimalDualBuffers& pd, const DataTermBuffers& data, const Buffer& tensor,
                            const Buffer& steps, const Buffer& mask, const PrimalDualParams& params) {
  cpu::primalDual(view(pd.u), view(pd.uBar), view(pd.v), view(pd.vBar), view(pd.p), view(pd.q), view(data.u0),
                  view(data.iu), view(data.iz), view(tensor), view(steps), view(mask), params);
}

void CpuBackend::median(const Buffer& dst, const Buffer& src, const Buffer& mask) {
  cpu::median(view(dst), view(src), view(mask));
}

void CpuBackend::accumulate(const Buffer& u, const Buffer& w, const Buffer& u0, const Buffer& tangent,
                            const Buffer& mask, float duMax) {
  cpu::accumulate(view(u), view(w), view(u0), view(tangent), view(mask), duMax);
}

}  // namespace cs::cpu

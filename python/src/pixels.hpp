// One pixel of a caller's array as the library's float gray, written once for the host
// (NumPy arrays) and the CUDA kernels (CuPy / PyTorch arrays) so both give the same bits.
// It mirrors the PNG reader (core/src/image_io.cpp, pngSample and convertRowToGray, which
// are not exported): 8-bit v -> float(v / 255.0), 16-bit v -> float(v / 65535.0), colour ->
// Rec. 601 luma computed in double on those floats and clamped at 1. Compiled without
// contraction (-ffp-contract=off, --fmad=false), as the reader is, so the sums round alike.
#pragma once
#include <cstring>

#ifdef __CUDACC__
#define CS_HD __host__ __device__
#else
#define CS_HD
#endif

namespace cs::py {

// The readers' limit; anything larger is refused before any work.
constexpr long long kMaxArraySide = 32768;

struct StridedPixels {
  const unsigned char* data;
  long long rowStride, colStride, chanStride;  // bytes; may be negative (flipped views)
  int channels;                                // 1 (gray), 3 or 4 (R G B [A]; alpha ignored)
};

CS_HD inline float sampleAt(const unsigned char* p, int type) {
  if (type == 0) return float(double(*p) / 255.0);
  if (type == 1) {
    unsigned short v;
    std::memcpy(&v, p, sizeof v);  // the caller's strides need not keep it aligned
    return float(double(v) / 65535.0);
  }
  float v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// Rec. 601 luma of three samples in double, clamped at 1 as the reader has it
// (std::min(1.0, luma)); NaN or +inf (only possible from float input) stays as it is so
// that compute() refuses it instead of seeing white.
CS_HD inline float lumaOf(float r, float g, float b) {
  const double luma = 0.299 * r + 0.587 * g + 0.114 * b;
  if (!(luma - luma == 0.0)) return float(luma);
  return float(luma < 1.0 ? luma : 1.0);
}

// type: 0 uint8, 1 uint16, 2 float32 (PixelType's order).
CS_HD inline float grayAt(const StridedPixels& s, int type, long long y, long long x) {
  const unsigned char* p = s.data + y * s.rowStride + x * s.colStride;
  if (s.channels < 3) return sampleAt(p, type);
  return lumaOf(sampleAt(p, type), sampleAt(p + s.chanStride, type), sampleAt(p + 2 * s.chanStride, type));
}

}  // namespace cs::py

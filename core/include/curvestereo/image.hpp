// Plain host images: the type every public function takes and returns.
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace cs {

struct Vec2f {
  float x = 0.f, y = 0.f;
};

// Row-major, top row first, no padding. Pixel (x, y) is data[y * width + x].
template <class T>
struct Image {
  int width = 0;
  int height = 0;
  std::vector<T> data;

  Image() = default;
  Image(int w, int h, T value = T()) : width(w), height(h), data(size_t(w) * size_t(h), value) {}

  T& operator()(int x, int y) { return data[size_t(y) * size_t(width) + size_t(x)]; }
  const T& operator()(int x, int y) const { return data[size_t(y) * size_t(width) + size_t(x)]; }
  bool empty() const { return data.empty(); }
  size_t size() const { return data.size(); }
  bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
};

using ImageF = Image<float>;
using ImageU8 = Image<uint8_t>;

// An 8-bit sample as the library reads it: v / 255, in float arithmetic. Every reader and
// every backend's byte upload uses this, so an 8-bit image gives the same floats whichever
// way it enters (float division of these values equals the rounded double v / 255.0).
inline float unitFromByte(uint8_t v) { return float(v) / 255.f; }
using FlowImage = Image<Vec2f>;

// Every recoverable failure of the library (bad input, unreadable file, missing
// backend) is reported as this exception; its what() is one line meant for users.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace cs

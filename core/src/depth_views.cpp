// Depth resampled into a virtual pinhole or an equirectangular image, and the file
// writers ROS / Open3D / PCL users need (see depth_views.hpp).
#include "curvestereo/depth_views.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "calib_common.hpp"
#include "curvestereo/camera.hpp"
#include "curvestereo/image_io.hpp"

namespace cs {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr int kMaxSide = 32768;

float nearest(const ImageF& radial, const Vec2<double>& p) {
  const double x = std::floor(p.x() + 0.5), y = std::floor(p.y() + 0.5);
  if (!(x >= 0 && y >= 0 && x < radial.width && y < radial.height)) return kNaN;  // also rejects NaN
  return radial(int(x), int(y));
}

// Bilinear only inside one surface: four finite, positive depths within the spread.
bool bilinear(const ImageF& radial, const Vec2<double>& p, float& out) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y());
  if (!(fx >= 0 && fy >= 0 && fx + 1 < radial.width && fy + 1 < radial.height)) return false;
  const int x = int(fx), y = int(fy);
  const float d[4] = {radial(x, y), radial(x + 1, y), radial(x, y + 1), radial(x + 1, y + 1)};
  float lo = d[0], hi = d[0];
  for (float v : d) {
    if (!(std::isfinite(v) && v > 0)) return false;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  if (hi > lo * (1.f + kBilinearSpread)) return false;
  const double ax = p.x() - fx, ay = p.y() - fy;
  out = float((1 - ay) * ((1 - ax) * d[0] + ax * d[1]) + ay * ((1 - ax) * d[2] + ax * d[3]));
  return true;
}

// The model is built from cam0.params without further checks, so they must be sound.
void checkInputs(const Camera& cam0, const ImageF& radial, const char* what) {
  cam0.validate();
  if (radial.width != cam0.width || radial.height != cam0.height)
    throw Error(std::string(what) + ": the depth image is " + std::to_string(radial.width) + "x" +
                std::to_string(radial.height) + " but camera 0 is " + std::to_string(cam0.width) + "x" +
                std::to_string(cam0.height));
}

// For each output pixel: its ray (any length), projected into camera 0, sampled; the
// depth scaled by factor(ray, |ray|).
template <class RayFn, class FactorFn>
ImageF resample(const Camera& cam0, const ImageF& radial, int width, int height, DepthSampling sampling, RayFn rayOf,
                FactorFn factor) {
  ImageF out(width, height, kNaN);
  const BuiltCamera built(cam0);
  std::visit(
      [&](const auto& model) {  // the model's own type: its project() inlined in the loop
        for (int y = 0; y < height; ++y)
          for (int x = 0; x < width; ++x) {
            const Vec3<double> ray = rayOf(x, y);
            Vec2<double> p;
            if (!model.project(ray, p, nullptr) || !cam0.inImage(p)) continue;
            const float r = sampleRadial(radial, p, sampling);
            if (!(r > 0)) continue;  // NaN (invalid) or 0 (ground truth's "outside the lens")
            out(x, y) = std::isinf(r) ? r : float(double(r) * factor(ray));
          }
      },
      built.model());
  return out;
}

}  // namespace

PinholeView PinholeView::fromFov(double horizontalFovDeg, int width, int height) {
  if (!(horizontalFovDeg >= 1 && horizontalFovDeg <= 179))
    throw Error("pinhole field of view must be 1 to 179 degrees, got " + calib::formatNumber(horizontalFovDeg));
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
    throw Error("pinhole image size must be 1 to " + std::to_string(kMaxSide) + " px per side, got " +
                std::to_string(width) + "x" + std::to_string(height));
  PinholeView v;
  v.width = width;
  v.height = height;
  v.fx = v.fy = 0.5 * width / std::tan(0.5 * horizontalFovDeg * M_PI / 180.0);
  v.cx = 0.5 * (width - 1);
  v.cy = 0.5 * (height - 1);
  return v;
}

float sampleRadial(const ImageF& radial, const Vec2<double>& p, DepthSampling sampling) {
  float value = 0;
  if (sampling == DepthSampling::Bilinear && bilinear(radial, p, value)) return value;
  return nearest(radial, p);
}

ImageF pinholeDepth(const Camera& cam0, const ImageF& radial, const PinholeView& view, DepthSampling sampling) {
  checkInputs(cam0, radial, "pinhole depth");
  return resample(
      cam0, radial, view.width, view.height, sampling, [&](int x, int y) { return view.ray(x, y); },
      [](const Vec3<double>& ray) { return ray.z() / ray.norm(); });
}

Vec3<double> equirectRay(double x, double y, int width) {
  const int height = width / 2;
  const double lon = ((x + 0.5) / width - 0.5) * 2.0 * M_PI;
  const double lat = ((y + 0.5) / height - 0.5) * M_PI;
  return Vec3<double>(std::cos(lat) * std::sin(lon), std::sin(lat), std::cos(lat) * std::cos(lon));
}

ImageF equirectRange(const Camera& cam0, const ImageF& radial, int width, DepthSampling sampling) {
  checkInputs(cam0, radial, "equirectangular range");
  if (width < 4 || width % 2 || width > kMaxSide)
    throw Error("equirectangular width must be even and 4 to " + std::to_string(kMaxSide) + " px, got " +
                std::to_string(width));
  return resample(
      cam0, radial, width, width / 2, sampling, [&](int x, int y) { return equirectRay(x, y, width); },
      [](const Vec3<double>&) { return 1.0; });
}

void writeCameraInfoYaml(const std::string& path, const PinholeView& v, const std::string& cameraName) {
  using calib::exactNumber;
  const std::string fx = exactNumber(v.fx), fy = exactNumber(v.fy), cx = exactNumber(v.cx), cy = exactNumber(v.cy);
  std::ostringstream os;
  os << "image_width: " << v.width << "\nimage_height: " << v.height << "\ncamera_name: " << cameraName << "\n"
     << "camera_matrix:\n  rows: 3\n  cols: 3\n  data: [" << fx << ", 0, " << cx << ", 0, " << fy << ", " << cy
     << ", 0, 0, 1]\n"
     << "distortion_model: plumb_bob\n"
     << "distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [0, 0, 0, 0, 0]\n"
     << "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n"
     << "projection_matrix:\n  rows: 3\n  cols: 4\n  data: [" << fx << ", 0, " << cx << ", 0, 0, " << fy << ", " << cy
     << ", 0, 0, 0, 1, 0]\n";
  calib::writeTextFile(path, os.str());
}

void writeDepthPngMillimetres(const std::string& path, const ImageF& zMetres) {
  // writePngGray16 stores round(v * 65535); v = mm / 65535 gives back mm exactly.
  ImageF scaled(zMetres.width, zMetres.height, 0.f);
  for (size_t i = 0; i < zMetres.size(); ++i) {
    const float z = zMetres.data[i];
    if (!(z > 0 && std::isfinite(z))) continue;
    const double mm = std::round(double(z) * 1000.0);
    if (mm >= 1 && mm <= 65535) scaled.data[i] = float(mm / 65535.0);
  }
  writePngGray16(path, scaled);
}

namespace {

void appendLittleEndian(std::string& out, float v) {
  uint32_t bits;
  std::memcpy(&bits, &v, 4);
  for (int i = 0; i < 4; ++i) out += char((bits >> (8 * i)) & 0xff);
}

}  // namespace

void writePcd(const std::string& path, const Image<Point3f>& points) {
  std::ostringstream header;
  header << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
         << "COUNT 1 1 1\nWIDTH " << points.width << "\nHEIGHT " << points.height
         << "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << points.size() << "\nDATA binary\n";
  std::string data = header.str();
  data.reserve(data.size() + 12 * points.size());
  for (const Point3f& p : points.data) {
    const bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    appendLittleEndian(data, finite ? p.x : kNaN);
    appendLittleEndian(data, finite ? p.y : kNaN);
    appendLittleEndian(data, finite ? p.z : kNaN);
  }
  calib::writeTextFile(path, data);
}

}  // namespace cs

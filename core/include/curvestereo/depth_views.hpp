// Depth in the forms that ROS, Open3D and mapping stacks take, from camera 0's radial
// depth (DepthMaps::radial): z-depth in a virtual pinhole camera with its CameraInfo
// (ROS REP 118), an equirectangular range image, and an organised point cloud (PCD).
// docs/guide.md "Outputs for ROS, Open3D and mapping" documents every file byte for byte.
#pragma once
#include <string>

#include "curvestereo/camera.hpp"
#include "curvestereo/image.hpp"
#include "curvestereo/triangulate.hpp"

namespace cs {

// A virtual pinhole camera at camera 0's centre with camera 0's orientation (x right,
// y down, z forward): square pixels, principal point at the image centre, no distortion.
struct PinholeView {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;

  // Horizontal field of view in degrees, in (0, 180): fx = fy = (width / 2) / tan(fov / 2),
  // cx = (width - 1) / 2, cy = (height - 1) / 2 (pixel centres at integers, as in OpenCV
  // and ROS). Throws cs::Error for a field of view or size out of range.
  static PinholeView fromFov(double horizontalFovDeg, int width, int height);
  // The ray of pixel (x, y), scaled to z = 1.
  Vec3<double> ray(double x, double y) const { return Vec3<double>((x - cx) / fx, (y - cy) / fy, 1.0); }
};

// How a depth is taken from the fisheye image at a sub-pixel position p.
//   Nearest:  the pixel nearest to p (round half up).
//   Bilinear: bilinear interpolation where the four pixels around p are all finite and
//             their largest depth is within kBilinearSpread of their smallest (one
//             surface); elsewhere (depth edges, the rim, the sky) nearest. Depths of two
//             surfaces are never blended.
enum class DepthSampling { Nearest, Bilinear };
constexpr float kBilinearSpread = 0.03f;

// Radial depth at sub-pixel position p of `radial`; NaN outside the image.
float sampleRadial(const ImageF& radial, const Vec2<double>& p, DepthSampling sampling);

// z-depth in `view` (metres; NaN where outside camera 0's image or where the radial depth
// is NaN or not positive; +inf where it is +inf): each pixel's ray goes through camera 0's
// model to a fisheye position p, and z = radial(p) * ray_z / |ray|. `radial` must be
// camera 0's size.
ImageF pinholeDepth(const Camera& cam0, const ImageF& radial, const PinholeView& view,
                    DepthSampling sampling = DepthSampling::Nearest);

// Unit ray of pixel (x, y) of a width x width/2 equirectangular image around camera 0's
// axis: longitude ((x + 0.5) / width - 0.5) * 360 deg (positive towards +x), latitude
// ((y + 0.5) / height - 0.5) * 180 deg (positive towards +y, down);
// ray = (cos(lat) sin(lon), sin(lat), cos(lat) cos(lon)).
Vec3<double> equirectRay(double x, double y, int width);
// Range image (radial metres) of width x width/2 pixels; NaN where the ray leaves camera
// 0's lens or image, or the depth is invalid. Throws cs::Error for width < 4 or odd.
ImageF equirectRange(const Camera& cam0, const ImageF& radial, int width,
                     DepthSampling sampling = DepthSampling::Nearest);

// ROS camera_info YAML (camera_calibration_parsers' format) of `view`: plumb_bob with
// zero distortion, identity rectification, P = [K | 0].
void writeCameraInfoYaml(const std::string& path, const PinholeView& view, const std::string& cameraName);

// 16-bit gray PNG of depth in millimetres (REP 118 16UC1): round(z * 1000); 0 where z is
// NaN, +inf, not positive, or above 65.535 m (no 16-bit value holds it).
void writeDepthPngMillimetres(const std::string& path, const ImageF& zMetres);

// Organised binary PCD (v0.7): FIELDS x y z, float32 little-endian, WIDTH x HEIGHT of the
// image, row-major, NaN for invalid points; byte for byte a PointCloud2 with point_step
// 12 and row_step 12 * width after the ASCII header.
void writePcd(const std::string& path, const Image<Point3f>& points);

}  // namespace cs

// Camera, the description of a camera as a calibration file gives it (model, image size,
// parameters), and BuiltCamera, a Camera with its model built once, which projects and
// unprojects (the model value types are in camera_models.hpp).
//
// Conventions: pixel (0,0) is the centre of the top-left pixel; camera frame
// x right, y down, z forward. unproject() returns a unit ray.
#pragma once
#include <string>
#include <vector>

#include "curvestereo/camera_models.hpp"

namespace cs {

class Camera {
 public:
  // params layout: [fx, fy, cx, cy, model-specific...]
  //   KannalaBrandt4: k1 k2 k3 k4     Unified: xi     ExtendedUnified: alpha beta
  //   DoubleSphere:   xi alpha        PinholeRadtan: k1 k2 p1 p2
  //   Mei:            xi k1 k2 p1 p2 (unified projection, then radtan)
  CameraModel model = CameraModel::KannalaBrandt4;
  int width = 0;
  int height = 0;
  std::vector<double> params;

  static Camera kannalaBrandt4(int w, int h, double fx, double fy, double cx, double cy, double k1 = 0, double k2 = 0,
                               double k3 = 0, double k4 = 0);
  static Camera unified(int w, int h, double fx, double fy, double cx, double cy, double xi);
  static Camera extendedUnified(int w, int h, double fx, double fy, double cx, double cy, double alpha, double beta);
  static Camera doubleSphere(int w, int h, double fx, double fy, double cx, double cy, double xi, double alpha);
  static Camera pinholeRadtan(int w, int h, double fx, double fy, double cx, double cy, double k1 = 0, double k2 = 0,
                              double p1 = 0, double p2 = 0);
  static Camera mei(int w, int h, double fx, double fy, double cx, double cy, double xi, double k1 = 0, double k2 = 0,
                    double p1 = 0, double p2 = 0);

  // px inside the image rectangle [-0.5, w-0.5] x [-0.5, h-0.5], shrunk by margin.
  bool inImage(const Vec2<double>& px, double margin = 0.0) const;
  // The camera for the same lens imaged at resolution scaled by s (pixel-centre aware).
  Camera scaled(double s) const;
  // The camera of the window of this image from pixel (x0, y0), width x height px: the
  // same rays, each at its pixel moved by (-x0, -y0).
  Camera cropped(int x0, int y0, int width, int height) const;
  // "kannala-brandt4", "unified", ... for messages.
  std::string modelName() const;
  // Throws cs::Error naming the problem if any parameter is non-finite or absurd.
  void validate() const;
};

// A Camera with its model built: the model struct of camera().model in double precision,
// whose constructor computed what every call needs (e.g. the Kannala-Brandt turning angle).
// Build one per camera, not per pixel, and project / unproject with it. An immutable value:
// copy it freely; its methods may run concurrently. After editing a Camera, build again.
class BuiltCamera {
 public:
  // Throws cs::Error when cam.params has not the model's number of entries (the values are
  // Camera::validate's to check).
  explicit BuiltCamera(const Camera& cam);

  const Camera& camera() const { return camera_; }
  const models::AnyModel<double>& model() const { return model_; }

  // False when p lies outside the model's valid region (then px/J are unspecified).
  // J (optional) is d(px)/d(p), 2x3.
  bool project(const Vec3<double>& p, Vec2<double>& px, Mat23<double>* J = nullptr) const;
  // False when px lies outside the model's valid region. ray has unit length.
  bool unproject(const Vec2<double>& px, Vec3<double>& ray) const;
  // The largest angle (radians) between the optical axis and a ray that the model
  // represents one-to-one (e.g. where a Kannala-Brandt polynomial stops increasing).
  double maxAngle() const;
  bool inImage(const Vec2<double>& px, double margin = 0.0) const { return camera_.inImage(px, margin); }

 private:
  Camera camera_;
  models::AnyModel<double> model_;
};

}  // namespace cs

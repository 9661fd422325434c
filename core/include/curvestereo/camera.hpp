// Camera models as small value types (project / unproject / Jacobian / valid region),
// and `Camera`, the run-time choice among them that a rig file describes.
//
// Conventions: pixel (0,0) is the centre of the top-left pixel; camera frame
// x right, y down, z forward. unproject() returns a unit ray.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

namespace cs {

template <class S>
using Vec2 = Eigen::Matrix<S, 2, 1>;
template <class S>
using Vec3 = Eigen::Matrix<S, 3, 1>;
template <class S>
using Mat23 = Eigen::Matrix<S, 2, 3>;

enum class CameraModel { KannalaBrandt4, Unified, ExtendedUnified, DoubleSphere, PinholeRadtan };

class Camera {
 public:
  // params layout: [fx, fy, cx, cy, model-specific...]
  //   KannalaBrandt4: k1 k2 k3 k4     Unified: xi     ExtendedUnified: alpha beta
  //   DoubleSphere:   xi alpha        PinholeRadtan: k1 k2 p1 p2
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

  // False when p lies outside the model's valid region (then px/J are unspecified).
  // J (optional) is d(px)/d(p), 2x3.
  template <class S>
  bool project(const Vec3<S>& p, Vec2<S>& px, Mat23<S>* J = nullptr) const;
  // False when px lies outside the model's valid region. ray has unit length.
  template <class S>
  bool unproject(const Vec2<S>& px, Vec3<S>& ray) const;

  // The largest angle (radians) between the optical axis and a ray that the model
  // represents one-to-one (e.g. where a Kannala-Brandt polynomial stops increasing).
  double maxAngle() const;
  // px inside the image rectangle [-0.5, w-0.5] x [-0.5, h-0.5], shrunk by margin.
  bool inImage(const Vec2<double>& px, double margin = 0.0) const;
  // The camera for the same lens imaged at resolution scaled by s (pixel-centre aware).
  Camera scaled(double s) const;
  // "kannala-brandt4", "unified", ... for messages.
  std::string modelName() const;
  // Throws cs::Error naming the problem if any parameter is non-finite or absurd.
  void validate() const;
};

}  // namespace cs

// Camera (the description: factories, scaling, validation) and BuiltCamera (its model built once).
#include "curvestereo/camera.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "curvestereo/camera_models.hpp"
#include "curvestereo/image.hpp"

namespace cs {

namespace {

Camera makeCamera(CameraModel model, int w, int h, std::vector<double> params) {
  Camera cam;
  cam.model = model;
  cam.width = w;
  cam.height = h;
  cam.params = std::move(params);
  return cam;
}

}  // namespace

Camera Camera::kannalaBrandt4(int w, int h, double fx, double fy, double cx, double cy, double k1, double k2, double k3,
                              double k4) {
  return makeCamera(CameraModel::KannalaBrandt4, w, h, {fx, fy, cx, cy, k1, k2, k3, k4});
}

Camera Camera::unified(int w, int h, double fx, double fy, double cx, double cy, double xi) {
  return makeCamera(CameraModel::Unified, w, h, {fx, fy, cx, cy, xi});
}

Camera Camera::extendedUnified(int w, int h, double fx, double fy, double cx, double cy, double alpha, double beta) {
  return makeCamera(CameraModel::ExtendedUnified, w, h, {fx, fy, cx, cy, alpha, beta});
}

Camera Camera::doubleSphere(int w, int h, double fx, double fy, double cx, double cy, double xi, double alpha) {
  return makeCamera(CameraModel::DoubleSphere, w, h, {fx, fy, cx, cy, xi, alpha});
}

Camera Camera::pinholeRadtan(int w, int h, double fx, double fy, double cx, double cy, double k1, double k2, double p1,
                             double p2) {
  return makeCamera(CameraModel::PinholeRadtan, w, h, {fx, fy, cx, cy, k1, k2, p1, p2});
}

Camera Camera::mei(int w, int h, double fx, double fy, double cx, double cy, double xi, double k1, double k2, double p1,
                   double p2) {
  return makeCamera(CameraModel::Mei, w, h, {fx, fy, cx, cy, xi, k1, k2, p1, p2});
}

bool Camera::inImage(const Vec2<double>& px, double margin) const {
  return px.x() >= -0.5 + margin && px.y() >= -0.5 + margin && px.x() <= width - 0.5 - margin &&
         px.y() <= height - 0.5 - margin;
}

// Pixel centres sit at integers, so the image edge -0.5 is what scales: c' + 0.5 = s (c + 0.5).
// Distortion acts on normalised coordinates and is unchanged.
Camera Camera::scaled(double s) const {
  Camera out = *this;
  out.width = int(std::lround(s * width));
  out.height = int(std::lround(s * height));
  if (out.params.size() >= 4) {
    out.params[0] = s * params[0];
    out.params[1] = s * params[1];
    out.params[2] = s * (params[2] + 0.5) - 0.5;
    out.params[3] = s * (params[3] + 0.5) - 0.5;
  }
  return out;
}

Camera Camera::cropped(int x0, int y0, int w, int h) const {
  if (x0 < 0 || y0 < 0 || w < 1 || h < 1 || x0 + w > width || y0 + h > height)
    throw Error("a window of " + std::to_string(w) + "x" + std::to_string(h) + " px at (" + std::to_string(x0) + ", " +
                std::to_string(y0) + ") does not fit a " + std::to_string(width) + "x" + std::to_string(height) +
                " image");
  Camera out = *this;
  out.width = w;
  out.height = h;
  if (out.params.size() >= 4) {
    out.params[2] -= x0;
    out.params[3] -= y0;
  }
  return out;
}

std::string Camera::modelName() const {
  std::string name = "unknown";
  models::visitModelType(model, [&](auto tag) { name = decltype(tag)::type::kName; });
  return name;
}

namespace {

// Builds "<model> camera WxH: <problem>" and throws it.
[[noreturn]] void fail(const Camera& cam, const std::string& problem) {
  std::ostringstream os;
  os.precision(10);
  os << cam.modelName() << " camera " << cam.width << "x" << cam.height << ": " << problem;
  throw Error(os.str());
}

std::string str(double v) {
  std::ostringstream os;
  os.precision(10);
  os << v;
  return os.str();
}

const char* paramName(CameraModel model, size_t i) {
  const char* name = "?";
  models::visitModelType(model, [&](auto tag) { name = decltype(tag)::type::kParamNames[i]; });
  return name;
}

// The model's own domain of its parameters (camera_models.hpp checkParams); cam has the
// model's number of parameters.
void checkModelParameters(const Camera& cam) {
  models::visitModelType(cam.model, [&](auto tag) {
    decltype(tag)::type::checkParams(cam.params.data(), [&](int i, const char* problem) {
      fail(cam, std::string(paramName(cam.model, size_t(i))) + " = " + str(cam.params[size_t(i)]) + " " + problem);
    });
  });
}

// cam, or cs::Error when its params have not the model's number of entries.
const Camera& withModelParams(const Camera& cam) {
  const int expected = models::paramCount(cam.model);
  if (int(cam.params.size()) != expected)
    fail(cam, "expected " + std::to_string(expected) + " parameters, got " + std::to_string(cam.params.size()));
  return cam;
}

}  // namespace

void Camera::validate() const {
  if (width <= 0 || height <= 0) fail(*this, "image size must be positive");
  withModelParams(*this);
  for (size_t i = 0; i < params.size(); ++i)
    if (!std::isfinite(params[i])) fail(*this, std::string(paramName(model, i)) + " is not finite");
  if (params[0] <= 0 || params[1] <= 0)
    fail(*this, "focal length (fx, fy) = (" + str(params[0]) + ", " + str(params[1]) + ") is not positive");
  // Focal lengths span about 0.15 (a 200+ degree fisheye) to 100 (a long telephoto) times
  // the image size; far outside that is a units mistake (metres, millimetres) or garbage.
  const double size = std::max(width, height);
  for (int i = 0; i < 2; ++i)
    if (params[size_t(i)] < 1e-2 * size || params[size_t(i)] > 1e4 * size)
      fail(*this, std::string(i ? "fy" : "fx") + " = " + str(params[size_t(i)]) +
                      " px is absurd for this image size (expected 0.01 to 10000 times " + str(size) + ")");
  // A principal point more than an image size away from the centre is a units or
  // ordering mistake (e.g. intrinsics in the wrong order), not a real lens.
  const double cxCentre = 0.5 * (width - 1), cyCentre = 0.5 * (height - 1);
  if (std::abs(params[2] - cxCentre) > width || std::abs(params[3] - cyCentre) > height)
    fail(*this, "principal point (" + str(params[2]) + ", " + str(params[3]) + ") is far outside the image");
  checkModelParameters(*this);
}

BuiltCamera::BuiltCamera(const Camera& cam)
    : camera_(withModelParams(cam)),
      model_(models::makeModel<double>(cam.model, cam.params.data(), cam.width, cam.height)) {}

bool BuiltCamera::project(const Vec3<double>& p, Vec2<double>& px, Mat23<double>* J) const {
  return std::visit([&](const auto& m) { return m.project(p, px, J); }, model_);
}

bool BuiltCamera::unproject(const Vec2<double>& px, Vec3<double>& ray) const {
  return std::visit([&](const auto& m) { return m.unproject(px, ray); }, model_);
}

double BuiltCamera::maxAngle() const {
  return std::visit([](const auto& m) { return m.maxAngle(); }, model_);
}

}  // namespace cs

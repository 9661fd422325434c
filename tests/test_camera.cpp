// Camera models: round trips, Jacobians, the principal point, valid regions, maxAngle,
// scaling and parameter validation.
#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "curvestereo/camera.hpp"
#include "curvestereo/camera_models.hpp"
#include "curvestereo/image.hpp"
#include "test_util.hpp"

using cs::BuiltCamera;
using cs::Camera;
using cs::Mat23;
using cs::Vec2;
using cs::Vec3;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A Camera with its model built in double (BuiltCamera) and in float (the precision GPU
// shaders may use), so that the tests below project and unproject in either.
class TestCamera : public Camera {
 public:
  TestCamera(const Camera& cam)  // NOLINT: implicit, so the cameras below read as plain Cameras
      : Camera(cam), built_(cam), single_(cs::models::makeModel<float>(model, params.data(), width, height)) {}

  bool project(const Vec3<double>& p, Vec2<double>& px, Mat23<double>* J = nullptr) const {
    return built_.project(p, px, J);
  }
  bool unproject(const Vec2<double>& px, Vec3<double>& ray) const { return built_.unproject(px, ray); }
  bool project(const Vec3<float>& p, Vec2<float>& px, Mat23<float>* J = nullptr) const {
    return std::visit([&](const auto& m) { return m.project(p, px, J); }, single_);
  }
  bool unproject(const Vec2<float>& px, Vec3<float>& ray) const {
    return std::visit([&](const auto& m) { return m.unproject(px, ray); }, single_);
  }
  double maxAngle() const { return built_.maxAngle(); }

 private:
  BuiltCamera built_;
  cs::models::AnyModel<float> single_;
};

struct NamedCamera {
  std::string name;
  TestCamera cam;
};

// Realistic calibrations of every model (values as published for T265 / EuRoC / TUM VI
// style lenses, rounded), plus the synthetic 180-degree lens and wider-than-180 lenses.
std::vector<NamedCamera> testCameras() {
  const double f180 = 800.0 / kPi;
  // 200 degrees across a 1000 px circle: theta = 100 deg at 500 px.
  const double f200 = 500.0 / (100.0 * kPi / 180.0);
  return {
      {"kb4 t265", Camera::kannalaBrandt4(848, 800, 285.7, 286.8, 420.1, 403.4, -0.0066, 0.0473, -0.0458, 0.0090)},
      {"kb4 equidistant 180", Camera::kannalaBrandt4(800, 800, f180, f180, 399.5, 399.5)},
      // theta_d keeps increasing up to pi: maxAngle = pi.
      {"kb4 200 deg", Camera::kannalaBrandt4(1000, 1000, f200, f200, 499.5, 499.5, 0.02, -0.003, 0, 0)},
      // theta_d turns around between 100 and 180 deg: maxAngle < pi.
      {"kb4 200 deg turning", Camera::kannalaBrandt4(1000, 1000, f200, f200, 499.5, 499.5, -0.01, -0.002, 0, 0)},
      {"ucm xi<1", Camera::unified(512, 512, 209.0, 209.5, 255.1, 256.3, 0.9)},
      {"ucm xi>1", Camera::unified(512, 512, 465.0, 464.0, 254.9, 256.8, 1.9)},
      {"eucm tumvi", Camera::extendedUnified(512, 512, 191.4, 191.3, 254.9, 256.9, 0.629, 1.18)},
      {"eucm alpha<0.5", Camera::extendedUnified(640, 480, 300.0, 300.0, 320.2, 240.3, 0.4, 0.9)},
      {"ds tumvi", Camera::doubleSphere(512, 512, 158.3, 158.2, 254.9, 256.9, -0.18, 0.59)},
      {"ds euroc", Camera::doubleSphere(752, 480, 349.7, 349.5, 365.0, 247.8, -0.209, 0.567)},
      {"ds wide xi>0", Camera::doubleSphere(800, 800, 200.0, 200.0, 399.5, 399.5, 0.2, 0.65)},
      {"pinhole radtan euroc", Camera::pinholeRadtan(752, 480, 458.654, 457.296, 367.215, 248.375, -0.28340811,
                                                     0.07395907, 0.00019359, 1.76187114e-05)},
      {"pinhole plain", Camera::pinholeRadtan(640, 480, 500.0, 500.0, 319.5, 239.5)},
      // MEI: a T265-like lens (xi < 1, no turning radius), a catadioptric-like xi > 1, and
      // one whose radial distortion turns (k2 = 0, k1 < 0: rMax = 1 / sqrt(-3 k1)).
      {"mei t265",
       Camera::mei(848, 800, 519.4431, 521.3283, 420.135, 403.394, 0.81, -0.3215268, 0.0570208, 0.00012, -8.0e-05)},
      {"mei xi>1", Camera::mei(752, 480, 1100.0, 1098.0, 375.2, 240.1, 2.1, -0.12, 0.09, -0.0003, 0.0002)},
      {"mei turning", Camera::mei(640, 640, 700.0, 700.0, 319.5, 319.5, 0.9, -0.3, 0.0, 0.0, 0.0)},
  };
}

Vec3<double> rayAt(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// Angles to test rays at: up to just inside the valid region, beyond 90 deg where the model allows.
std::vector<double> testAngles(const TestCamera& cam) {
  const double top = cam.maxAngle() - 1e-3;
  std::vector<double> angles;
  for (int i = 0; i <= 40; ++i) angles.push_back(top * i / 40.0);
  return angles;
}

// Central differences with a step well inside the distance to the nearest singularity:
// the back pole of a >180 deg lens (px varies on the scale of r there) and the edge of
// the valid region, where px runs off to infinity for UCM xi<1 / EUCM alpha<0.5.
Mat23<double> numericJacobian(const TestCamera& cam, const Vec3<double>& p, double angleToEdge) {
  Mat23<double> J;
  const double h = 1e-5 * std::min({p.norm(), std::hypot(p.x(), p.y()), p.norm() * angleToEdge});
  for (int k = 0; k < 3; ++k) {
    Vec3<double> plus = p, minus = p;
    plus[k] += h;
    minus[k] -= h;
    Vec2<double> a, b;
    REQUIRE(cam.project(plus, a));
    REQUIRE(cam.project(minus, b));
    J.col(k) = (a - b) / (2 * h);
  }
  return J;
}

// On the optical axis every model is a pinhole of focal f * gain: UCM and DS divide by
// (1 + xi) z there, the others by z.
double axisGain(const Camera& cam) {
  if (cam.model == cs::CameraModel::Unified || cam.model == cs::CameraModel::DoubleSphere ||
      cam.model == cs::CameraModel::Mei)
    return 1.0 / (1.0 + cam.params[4]);
  return 1.0;
}

}  // namespace

TEST_CASE("project(unproject(px)) == px over the image") {
  for (const auto& [name, cam] : testCameras()) {
    CAPTURE(name);
    REQUIRE_NOTHROW(cam.validate());
    int valid = 0, total = 0;
    for (double y = -0.5; y <= cam.height - 0.5; y += 7.3) {
      for (double x = -0.5; x <= cam.width - 0.5; x += 7.3) {
        ++total;
        const Vec2<double> px(x, y);
        Vec3<double> ray;
        if (!cam.unproject(px, ray)) continue;
        ++valid;
        CHECK(std::abs(ray.norm() - 1) < 1e-12);
        Vec2<double> back;
        REQUIRE(cam.project(ray, back));
        CHECK((back - px).norm() < 1e-9);

        const Vec2<float> pxf = px.cast<float>();
        Vec3<float> rayf;
        if (!cam.unproject(pxf, rayf)) continue;  // float may lose the last pixels at a region edge
        Vec2<float> backf;
        REQUIRE(cam.project(rayf, backf));
        CHECK((backf - pxf).norm() < 1e-3f);
      }
    }
    // Most of the image must be valid, or the loop above proves nothing. (The wide
    // double sphere lens leaves the corners outside its image circle.)
    CHECK(valid > total * 3 / 5);
  }
}

TEST_CASE("unproject(project(p)) == p/|p|, beyond 90 deg where the model allows") {
  for (const auto& [name, cam] : testCameras()) {
    CAPTURE(name);
    int beyond90 = 0;
    for (double theta : testAngles(cam)) {
      for (double phi = -3.0; phi < 3.2; phi += 0.7) {
        const Vec3<double> dir = rayAt(theta, phi);
        const Vec3<double> p = 3.7 * dir;
        Vec2<double> px;
        REQUIRE(cam.project(p, px));  // everything below maxAngle is valid
        Vec3<double> ray;
        REQUIRE(cam.unproject(px, ray));
        CHECK((ray - dir).norm() < 1e-9);
        if (theta > kPi / 2) ++beyond90;

        Vec2<float> pxf;
        REQUIRE(cam.project(p.cast<float>().eval(), pxf));
        Vec3<float> rayf;
        if (theta < cam.maxAngle() - 1e-2) {  // float rounding may step over the very edge
          REQUIRE(cam.unproject(pxf, rayf));
          CHECK((rayf.cast<double>() - dir).norm() < 1e-5);
        }
      }
    }
    if (cam.maxAngle() > kPi / 2 + 0.01) CHECK(beyond90 > 0);
  }
}

TEST_CASE("Jacobian matches central differences") {
  for (const auto& [name, cam] : testCameras()) {
    CAPTURE(name);
    for (double theta : testAngles(cam)) {
      if (theta == 0) continue;  // the axis has its own test below
      for (double phi = -2.9; phi < 3.2; phi += 1.1) {
        const Vec3<double> p = 2.3 * rayAt(theta, phi);
        Vec2<double> px;
        Mat23<double> J;
        REQUIRE(cam.project(p, px, &J));
        const Mat23<double> Jnum = numericJacobian(cam, p, cam.maxAngle() - theta);
        const double scale = J.cwiseAbs().maxCoeff();
        CAPTURE(theta);
        CHECK((J - Jnum).cwiseAbs().maxCoeff() < 1e-6 * scale);

        // Float: compared with the double reference, not float differences (whose
        // rounding, eps_f * |px| / h, swamps any useful bound). Forming the derivative
        // loses a few digits to cancellation (e.g. KB4's A = (d' z / rho^2 - s) / r^2),
        // so allow ~1000 float epsilons. Right at the edge of the valid region of UCM
        // xi<1 / EUCM alpha<0.5 the denominator den -> 0 carries a float rounding of
        // eps_f |p|, i.e. a relative error eps_f |p| / den: skip the last 0.02 rad there.
        if (cam.maxAngle() - theta < 0.02) continue;
        Vec2<float> pxf;
        Mat23<float> Jf;
        REQUIRE(cam.project(p.cast<float>().eval(), pxf, &Jf));
        CHECK((Jf.cast<double>() - Jnum).cwiseAbs().maxCoeff() < 1e-4 * scale);
      }
    }
  }
}

TEST_CASE("the principal point and the optical axis are regular") {
  for (const auto& [name, cam] : testCameras()) {
    CAPTURE(name);
    const double gain = axisGain(cam);
    const double fx = cam.params[0] * gain, fy = cam.params[1] * gain;
    const Vec2<double> c(cam.params[2], cam.params[3]);
    Vec3<double> ray;
    REQUIRE(cam.unproject(c, ray));
    CHECK((ray - Vec3<double>(0, 0, 1)).norm() < 1e-15);

    const double z = 2.0;
    Vec2<double> px;
    Mat23<double> J;
    REQUIRE(cam.project(Vec3<double>(0, 0, z), px, &J));
    CHECK((px - c).norm() < 1e-12);
    REQUIRE(J.allFinite());
    Mat23<double> expected;  // every model is a pinhole with focal f to first order on the axis
    expected << fx / z, 0, 0, 0, fy / z, 0;
    CHECK((J - expected).norm() < 1e-12 * fx);

    // Just off the axis the Jacobian must be continuous (no 0/0, no cancellation blow-up).
    for (double r : {1e-300, 1e-12, 1e-9, 1e-6}) {
      Mat23<double> Jr;
      REQUIRE(cam.project(Vec3<double>(r, -0.5 * r, z), px, &Jr));
      REQUIRE(Jr.allFinite());
      CHECK((Jr - expected).norm() < 1e-6 * fx);
    }
    Mat23<float> Jf;
    Vec2<float> pxf;
    REQUIRE(cam.project(Vec3<float>(1e-20f, 0, 2), pxf, &Jf));
    CHECK(Jf.allFinite());
    CHECK((Jf.cast<double>() - expected).norm() < 1e-5 * fx);
    Vec3<float> rayf;
    REQUIRE(cam.unproject(c.cast<float>().eval(), rayf));
    CHECK(rayf.allFinite());
  }
}

TEST_CASE("maxAngle is where the valid region ends") {
  for (const auto& [name, cam] : testCameras()) {
    CAPTURE(name);
    const double maxAngle = cam.maxAngle();
    REQUIRE(maxAngle > 0);
    REQUIRE(maxAngle <= kPi);
    if (cam.model == cs::CameraModel::PinholeRadtan) continue;  // its maxAngle is the image corner
    if (maxAngle >= kPi - 1e-9) continue;                       // the whole sphere but the back axis
    Vec2<double> px;
    for (double phi : {0.3, 2.0, -1.2}) {
      CHECK(cam.project(rayAt(maxAngle - 1e-6, phi), px));
      CHECK_FALSE(cam.project(rayAt(maxAngle + 1e-6, phi), px));
    }
  }
  const double f180 = 800.0 / kPi;
  CHECK(BuiltCamera(Camera::kannalaBrandt4(800, 800, f180, f180, 399.5, 399.5)).maxAngle() == doctest::Approx(kPi));
  CHECK(BuiltCamera(Camera::unified(512, 512, 200, 200, 256, 256, 0.9)).maxAngle() == doctest::Approx(std::acos(-0.9)));
  CHECK(BuiltCamera(Camera::unified(512, 512, 200, 200, 256, 256, 1.9)).maxAngle() ==
        doctest::Approx(std::acos(-1 / 1.9)));
  CHECK(BuiltCamera(Camera::unified(512, 512, 200, 200, 256, 256, 0.0)).maxAngle() == doctest::Approx(kPi / 2));
  // Undistorted pinhole: the corner ray at (-0.5, -0.5).
  const double corner = std::atan(std::hypot(320.0, 240.0) / 500.0);
  CHECK(BuiltCamera(Camera::pinholeRadtan(640, 480, 500, 500, 319.5, 239.5)).maxAngle() == doctest::Approx(corner));
}

TEST_CASE("Kannala-Brandt: turning point and invalid region") {
  const double f200 = 500.0 / (100.0 * kPi / 180.0);
  const TestCamera cam = Camera::kannalaBrandt4(1000, 1000, f200, f200, 499.5, 499.5, -0.01, -0.002, 0, 0);
  const double tm = cam.maxAngle();
  // d theta_d / d theta = 1 + 3 k1 t^2 + 5 k2 t^4 vanishes at maxAngle.
  CHECK(1 + 3 * -0.01 * tm * tm + 5 * -0.002 * std::pow(tm, 4) == doctest::Approx(0).epsilon(1e-12));
  CHECK(tm > 100.0 * kPi / 180.0);

  Vec2<double> px;
  CHECK_FALSE(cam.project(Vec3<double>(0, 0, -1), px));  // straight back: theta = pi
  CHECK_FALSE(cam.project(Vec3<double>(0, 0, 0), px));
  CHECK_FALSE(cam.project(Vec3<double>(NAN, 0, 1), px));
  Vec3<double> ray;
  CHECK_FALSE(cam.unproject(Vec2<double>(499.5 + 5000, 499.5), ray));  // beyond theta_d(maxAngle)
  CHECK_FALSE(cam.unproject(Vec2<double>(NAN, 1), ray));

  // The synthetic scenes' lens: radius 400 px is exactly 90 deg.
  const double f180 = 800.0 / kPi;
  const TestCamera equi = Camera::kannalaBrandt4(800, 800, f180, f180, 399.5, 399.5);
  REQUIRE(equi.unproject(Vec2<double>(399.5 + 400, 399.5), ray));
  CHECK((ray - Vec3<double>(1, 0, 0)).norm() < 1e-12);
}

TEST_CASE("unified family and pinhole: invalid regions") {
  Vec2<double> px;
  Vec3<double> ray;
  const TestCamera ucm = Camera::unified(512, 512, 465, 464, 254.9, 256.8, 1.9);
  CHECK_FALSE(ucm.project(rayAt(std::acos(-1 / 1.9) + 0.01, 0.4), px));
  // Beyond r^2 = 1 / (xi^2 - 1) no ray projects.
  CHECK_FALSE(ucm.unproject(Vec2<double>(254.9 + 465 * 0.7, 256.8), ray));

  const TestCamera eucm = Camera::extendedUnified(512, 512, 191.4, 191.3, 254.9, 256.9, 0.629, 1.18);
  CHECK_FALSE(eucm.project(Vec3<double>(0, 0, -1), px));
  CHECK_FALSE(eucm.unproject(Vec2<double>(254.9 + 191.4 * 2.0, 256.9), ray));  // r^2 > 1/(beta (2 alpha - 1))

  const TestCamera ds = Camera::doubleSphere(512, 512, 158.3, 158.2, 254.9, 256.9, -0.18, 0.59);
  CHECK_FALSE(ds.project(Vec3<double>(0.1, 0, -1), px));
  CHECK_FALSE(ds.unproject(Vec2<double>(254.9 + 158.3 * 2.5, 256.9), ray));  // r^2 > 1/(2 alpha - 1)

  const TestCamera pin = Camera::pinholeRadtan(752, 480, 458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907,
                                               0.00019359, 1.76187114e-05);
  CHECK_FALSE(pin.project(Vec3<double>(0.1, 0.1, 0), px));
  CHECK_FALSE(pin.project(Vec3<double>(0.1, 0.1, -1), px));

  Camera broken = pin;
  broken.params.pop_back();  // wrong parameter count: refused when built, not read out of bounds
  CHECK_THROWS_AS(BuiltCamera{broken}, cs::Error);
}

TEST_CASE("MEI: unified without distortion; the turning radius bounds the valid region") {
  // With k1 = k2 = p1 = p2 = 0 MEI is the unified model, ray for ray.
  const TestCamera mei = Camera::mei(512, 512, 465, 464, 254.9, 256.8, 1.9);
  const TestCamera ucm = Camera::unified(512, 512, 465, 464, 254.9, 256.8, 1.9);
  CHECK(mei.maxAngle() == doctest::Approx(ucm.maxAngle()));
  for (double theta : {0.0, 0.3, 1.0, 1.9}) {
    Vec2<double> a, b;
    REQUIRE(mei.project(rayAt(theta, 0.7), a));
    REQUIRE(ucm.project(rayAt(theta, 0.7), b));
    CHECK((a - b).norm() < 1e-12);
  }
  // k1 = -0.3, k2 = 0: r (1 + k1 r^2) turns at r^2 = 1 / 0.9; the ray there is maxAngle.
  const TestCamera turning = Camera::mei(640, 640, 350, 350, 319.5, 319.5, 0.9, -0.3);
  const double r = std::sqrt(1 / 0.9), xi = 0.9;
  const double f = (xi + std::sqrt(1 + (1 - xi * xi) * r * r)) / (1 + r * r);
  CHECK(turning.maxAngle() == doctest::Approx(std::atan2(f * r, f - xi)));
  Vec2<double> px;
  Vec3<double> ray;
  CHECK_FALSE(turning.project(rayAt(turning.maxAngle() + 1e-3, 0.2), px));
  // Beyond the distorted image of rMax (r (1 + k1 r^2) = 2 r / 3) no pixel unprojects.
  CHECK_FALSE(turning.unproject(Vec2<double>(319.5 + 350 * (2 * r / 3) * 1.01, 319.5), ray));
  CHECK(turning.unproject(Vec2<double>(319.5 + 350 * (2 * r / 3) * 0.99, 319.5), ray));
  CHECK(Camera::mei(512, 512, 465, 464, 254.9, 256.8, 1.9).modelName() == "mei");
}

TEST_CASE("scaled() keeps the image of every ray at the scaled pixel") {
  const TestCamera cam = Camera::kannalaBrandt4(848, 800, 285.7, 286.8, 420.1, 403.4, -0.0066, 0.0473, -0.0458, 0.0090);
  const TestCamera half = cam.scaled(0.5);
  CHECK(half.width == 424);
  CHECK(half.height == 400);
  CHECK(cam.scaled(1.0 / 3).width == 283);
  const Vec3<double> p(0.3, -0.2, 1.0);
  Vec2<double> a, b;
  REQUIRE(cam.project(p, a));
  REQUIRE(half.project(p, b));
  // Pixel edges scale: (b + 0.5) = s (a + 0.5).
  CHECK((b - (0.5 * (a.array() + 0.5) - 0.5).matrix()).norm() < 1e-12);
}

TEST_CASE("cropped() keeps every ray at its pixel moved by the window's origin") {
  const TestCamera cam = Camera::kannalaBrandt4(848, 800, 285.7, 286.8, 420.1, 403.4, -0.0066, 0.0473, -0.0458, 0.0090);
  const TestCamera window = cam.cropped(300, 120, 400, 500);
  CHECK(window.width == 400);
  CHECK(window.height == 500);
  for (const Vec3<double>& p : {Vec3<double>(0.3, -0.2, 1.0), Vec3<double>(-0.9, 0.4, 0.2)}) {
    Vec2<double> a, b;
    REQUIRE(cam.project(p, a));
    REQUIRE(window.project(p, b));
    CHECK((b - (a - Vec2<double>(300, 120))).norm() < 1e-9);
  }
  CHECK_THROWS_WITH_AS(cam.cropped(500, 0, 400, 10), "a window of 400x10 px at (500, 0) does not fit a 848x800 image",
                       cs::Error);
  CHECK_THROWS_AS(cam.cropped(-1, 0, 10, 10), cs::Error);
  CHECK_THROWS_AS(cam.cropped(0, 0, 0, 10), cs::Error);
}

TEST_CASE("inImage uses the pixel-edge rectangle") {
  const Camera cam = Camera::pinholeRadtan(640, 480, 500, 500, 319.5, 239.5);
  CHECK(cam.inImage(Vec2<double>(-0.5, -0.5)));
  CHECK(cam.inImage(Vec2<double>(639.5, 479.5)));
  CHECK_FALSE(cam.inImage(Vec2<double>(639.6, 100)));
  CHECK_FALSE(cam.inImage(Vec2<double>(2, 2), 3.0));
  CHECK(cam.inImage(Vec2<double>(2.5, 2.5), 3.0));
}

namespace {

std::string validationError(const Camera& cam) {
  try {
    cam.validate();
  } catch (const cs::Error& e) {
    return e.what();
  }
  return "<no error>";
}

}  // namespace

TEST_CASE("validate() names the problem in one line") {
  const Camera kb = Camera::kannalaBrandt4(848, 800, 285.7, 286.8, 420.1, 403.4, -0.0066, 0.0473, -0.0458, 0.0090);
  CHECK(validationError(kb) == "<no error>");

  struct Case {
    Camera cam;
    std::string expected;
  };
  Camera noParams = kb;
  noParams.params.resize(3);
  const std::vector<Case> cases = {
      {Camera::kannalaBrandt4(848, 800, -285.7, 286.8, 420.1, 403.4), "focal length"},
      {Camera::kannalaBrandt4(848, 800, 285.7, NAN, 420.1, 403.4), "fy is not finite"},
      {Camera::kannalaBrandt4(848, 800, 285.7, 286.8, 420.1, 403.4, 0, INFINITY), "k2 is not finite"},
      {Camera::kannalaBrandt4(0, 800, 285.7, 286.8, 420.1, 403.4), "image size"},
      {Camera::kannalaBrandt4(848, 800, 285.7, 286.8, 4201, 403.4), "principal point"},
      {Camera::unified(512, 512, 200, 200, 256, 256, -0.1), "xi"},
      {Camera::extendedUnified(512, 512, 200, 200, 256, 256, 1.5, 1.0), "alpha"},
      {Camera::extendedUnified(512, 512, 200, 200, 256, 256, 0.6, 0.0), "beta"},
      {Camera::doubleSphere(512, 512, 200, 200, 256, 256, -1.5, 0.6), "xi"},
      {Camera::doubleSphere(512, 512, 200, 200, 256, 256, 0.1, -0.2), "alpha"},
      {noParams, "expected 8 parameters"},
  };
  for (const auto& c : cases) {
    const std::string msg = validationError(c.cam);
    CAPTURE(msg);
    CHECK(msg.find(c.expected) != std::string::npos);
    CHECK(msg.find(c.cam.modelName()) != std::string::npos);
    CHECK(msg.find('\n') == std::string::npos);
  }
}

TEST_CASE("modelName") {
  CHECK(Camera::kannalaBrandt4(8, 8, 1, 1, 4, 4).modelName() == "kannala-brandt4");
  CHECK(Camera::unified(8, 8, 1, 1, 4, 4, 1).modelName() == "unified");
  CHECK(Camera::extendedUnified(8, 8, 1, 1, 4, 4, 0.5, 1).modelName() == "extended-unified");
  CHECK(Camera::doubleSphere(8, 8, 1, 1, 4, 4, 0, 0.5).modelName() == "double-sphere");
  CHECK(Camera::pinholeRadtan(8, 8, 1, 1, 4, 4).modelName() == "pinhole-radtan");
}

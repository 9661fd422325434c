// The synthetic renderer: determinism, exact ground-truth depth, consistency of the two
// views with the camera models and the pose, sky / outside-the-disc conventions, other
// camera models and fields of view beyond 180 degrees; and the sequences of
// `synth --sequence` (files, timestamps, poses, the mover, consistency across frames).
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "cli_util.hpp"
#include "curvestereo/camera.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/rig.hpp"
#include "synth/random.hpp"
#include "synth/rig.hpp"
#include "synth/scene.hpp"
#include "synth/sequence.hpp"
#include "test_util.hpp"

using cs::BuiltCamera;
using cs::Camera;
using cs::ImageF;
using cs::Vec2;
using cs::Vec3;
using Eigen::Vector3d;
using namespace cs::synth;

namespace {

constexpr double kPi = 3.14159265358979323846;

SynthConfig smallConfig(int size, int samples) {
  SynthConfig cfg;
  cfg.camera = defaultFisheye(size);
  cfg.samplesPerAxis = samples;
  cfg.nearest = 1.0;
  return cfg;
}

// A wider-than-180 lens: equidistant, 220 deg across the image width.
Camera fisheye220(int size) {
  const double f = 0.5 * size / (110.0 * kPi / 180.0);
  return Camera::kannalaBrandt4(size, size, f, f, 0.5 * (size - 1), 0.5 * (size - 1));
}

// TUM-VI-like double sphere lens (about 195 deg), scaled to `size`.
Camera doubleSphere195(int size) {
  return Camera::doubleSphere(512, 512, 158.3, 158.2, 254.9, 256.9, -0.18, 0.59).scaled(size / 512.0);
}

Vector3d pixelRay(const BuiltCamera& cam, double x, double y) {
  Vec3<double> ray;
  REQUIRE(cam.unproject(Vec2<double>(x, y), ray));
  return ray.normalized();
}

double bilinear(const ImageF& img, double x, double y) {
  const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  auto at = [&](int xi, int yi) {
    return double(img(std::clamp(xi, 0, img.width - 1), std::clamp(yi, 0, img.height - 1)));
  };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
         fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

// Distance along the ray to the first surface found by sphere tracing the scene's
// distance field: independent of the ray-intersection code. +inf if nothing is met.
double sphereTrace(const Scene& scene, const Vector3d& origin, const Vector3d& dir, double limit) {
  double t = 0.0;
  for (int step = 0; step < 20000 && t < limit; ++step) {
    const double d = scene.signedDistance(origin + t * dir);
    if (d < 1e-7 * (1.0 + t)) return t;
    t += d;
  }
  return std::numeric_limits<double>::infinity();
}

// Share of sampled surface pixels whose depth agrees with sphere tracing, and the
// largest distance-field value at the ground-truth points (should be ~0).
struct DepthCheck {
  int checked = 0, agreeing = 0;
  double worstOffSurface = 0.0;
};

DepthCheck checkDepth(const Scene& scene, const Camera& camera, const Pose& pose, const ImageF& depth, int stride) {
  const BuiltCamera cam(camera);
  DepthCheck c;
  for (int y = 0; y < depth.height; y += stride)
    for (int x = 0; x < depth.width; x += stride) {
      const double d = depth(x, y);
      if (!(d > 0.0) || std::isinf(d)) continue;
      const Vector3d dir = pose.rotation * pixelRay(cam, x, y);
      const Vector3d point = pose.centre + d * dir;
      c.worstOffSurface = std::max(c.worstOffSurface, std::abs(scene.signedDistance(point)) / d);
      const double traced = sphereTrace(scene, pose.centre, dir, 2.0 * d);
      ++c.checked;
      if (std::abs(traced - d) < 1e-4 * d) ++c.agreeing;
    }
  return c;
}

// Pixels near the rim of a fisheye disc are darkened by the anti-aliasing filter (a
// property of the image, not of the scene), so the comparisons stay inside 170 deg.
constexpr double kRimCosine = 0.087;

// No depth edge in the 3x3 neighbourhood: anti-aliased pixels mix two surfaces.
bool smoothDepthAround(const ImageF& depth, int x, int y) {
  const float centre = depth(x, y);
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      if (!depth.inside(x + dx, y + dy)) return false;
      const float d = depth(x + dx, y + dy);
      if (std::isinf(centre) != std::isinf(d)) return false;
      if (!std::isinf(d) && !(std::abs(d - centre) < 0.05f * centre)) return false;
    }
  return true;
}

// Mean |I0(x) - I1(x')| over ground-truth correspondences x -> x' seen by both cameras
// (depth_right agrees), and the same for random pairs, as a scale. shift: the image
// displacement (px) that best explains the residuals I0(x) - I1(x') by the gradient
// of I1 (least squares); a renderer off by a fraction of a pixel shows up here.
struct Consistency {
  double matched = 0.0, random = 0.0;
  int count = 0;
  Eigen::Vector2d shift = Eigen::Vector2d::Zero();
};

Consistency viewConsistency(const SynthPair& p) {
  Consistency c;
  cs::synth::Random pick(99);
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  const BuiltCamera cam0(p.rig.cam0), cam1(p.rig.cam1);
  for (int y = 0; y < p.left.height; ++y)
    for (int x = 0; x < p.left.width; ++x) {
      const double d = p.depthLeft(x, y);
      if (!(d > 0.0) || !smoothDepthAround(p.depthLeft, x, y)) continue;
      const Vector3d ray0 = pixelRay(cam0, x, y);
      if (ray0.z() < kRimCosine) continue;
      // A sky point is a direction: only the rotation moves it.
      const Vector3d x1 = std::isinf(d) ? Vector3d(p.rig.R * ray0) : Vector3d(p.rig.R * (d * ray0) + p.rig.t);
      Vec2<double> px;
      if (x1.normalized().z() < kRimCosine) continue;
      if (!cam1.project(Vec3<double>(x1), px) || !cam1.inImage(px, 2.0)) continue;
      const double d1 = p.depthRight(int(std::lround(px.x())), int(std::lround(px.y())));
      if (!(d1 > 0.0)) continue;
      const bool visible = std::isinf(d) ? std::isinf(d1) : std::abs(d1 - x1.norm()) < 0.02 * x1.norm();
      if (!visible) continue;
      const double residual = p.left(x, y) - bilinear(p.right, px.x(), px.y());
      c.matched += std::abs(residual);
      const Eigen::Vector2d gradient(
          0.5 * (bilinear(p.right, px.x() + 1, px.y()) - bilinear(p.right, px.x() - 1, px.y())),
          0.5 * (bilinear(p.right, px.x(), px.y() + 1) - bilinear(p.right, px.x(), px.y() - 1)));
      normal += gradient * gradient.transpose();
      rhs += gradient * residual;
      const int rx = pick.integer(0, p.right.width - 1), ry = pick.integer(0, p.right.height - 1);
      c.random += std::abs(p.left(x, y) - p.right(rx, ry));
      ++c.count;
    }
  if (c.count > 0) {
    c.matched /= c.count;
    c.random /= c.count;
    c.shift = normal.ldlt().solve(rhs);
  }
  return c;
}

// Sky at (x, y) and its 8 neighbours: no anti-aliased object edge mixes into the pixel.
bool skyAround(const ImageF& depth, int x, int y) {
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx)
      if (!depth.inside(x + dx, y + dy) || !std::isinf(depth(x + dx, y + dy))) return false;
  return true;
}

void checkConsistency(const Consistency& c) {
  INFO("mean |I0 - I1|: matched " << c.matched << ", random " << c.random << " over " << c.count << " pixels; shift "
                                  << c.shift.transpose() << " px");
  CHECK(c.count > 3000);
  CHECK(c.matched < 0.1 * c.random);
  CHECK(c.shift.norm() < 0.05);
}

int countValid(const ImageF& depth) {
  int n = 0;
  for (float d : depth.data) n += d > 0.f;
  return n;
}

}  // namespace

TEST_CASE("synth: rig conventions of the motions") {
  SynthConfig cfg = smallConfig(64, 1);
  cfg.baseline = 0.3;
  cfg.rotationDeg = 3.0;
  for (const char* motion : {"binocular", "forward", "sideways"}) {
    cfg.motion = motion;
    const cs::Rig rig = makeRig(cfg);
    const Vector3d centre1 = -rig.R.transpose() * rig.t;
    const Vector3d expected = cfg.motion == "binocular" ? Vector3d(0.3, 0, 0)
                              : cfg.motion == "forward" ? Vector3d(0.06, 0, 0.3)
                                                        : Vector3d(0.3, 0, 0.09);
    CHECK((centre1 - expected).norm() < 1e-12);
    // Camera 1's optical axis (in camera 0) is turned by +3 deg about y: towards +x.
    const Vector3d axis1 = rig.R.transpose() * Vector3d::UnitZ();
    CHECK(axis1.x() == doctest::Approx(std::sin(3.0 * kPi / 180.0)).epsilon(1e-12));
    CHECK((rig.R * rig.R.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-12);
  }
  cfg.motion = "diagonal";
  CHECK_THROWS_AS(makeRig(cfg), cs::Error);
  cfg.motion = "binocular";
  cfg.scene = "forest";
  CHECK_THROWS_AS(renderPair(cfg), cs::Error);
}

TEST_CASE("synth: deterministic for a seed, different across seeds") {
  for (const char* kind : {"urban", "indoor"}) {
    // 48 px under the sanitizers (a third of the rays): every pixel's rays are cast alike,
    // so the same seed gives the same bits at any size.
    SynthConfig cfg = smallConfig(CS_SANITIZED ? 48 : 80, 2);
    cfg.scene = kind;
    cfg.seed = 5;
    const SynthPair a = renderPair(cfg), b = renderPair(cfg);
    CHECK(a.left.data == b.left.data);
    CHECK(a.right.data == b.right.data);
    CHECK(a.depthLeft.data == b.depthLeft.data);
    CHECK(a.depthRight.data == b.depthRight.data);
    cfg.seed = 6;
    const SynthPair c = renderPair(cfg);
    CHECK(c.left.data != a.left.data);
  }
}

TEST_CASE("synth: depth of a single analytic plane is exact") {
  Scene scene;
  scene.add(makePlane(Vector3d(0, 0, 4.0), Vector3d(0, 0, -1), Material(), "wall"));  // z = 4, facing the camera
  scene.setDetail(Vector3d::Zero(), kPi / 96);
  const Camera cam = defaultFisheye(96);
  Pose pose;  // camera frame = world frame: the wall is fronto-parallel at z = 4
  RenderOptions options;
  options.samplesPerAxis = 2;
  ImageF image, depth;
  renderView(scene, cam, pose, options, image, depth);
  const BuiltCamera built(cam);
  int checked = 0;
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x) {
      if (!(depth(x, y) > 0.f)) continue;
      const Vector3d ray = pixelRay(built, x, y);
      if (ray.z() <= 1e-9) {
        CHECK(std::isinf(depth(x, y)));  // rays at or beyond 90 deg never meet the wall
        continue;
      }
      CHECK(depth(x, y) == doctest::Approx(4.0 / ray.z()).epsilon(2e-7));
      if (ray.z() > 0.1) {  // away from the rim, which the filter darkens
        CHECK(image(x, y) >= 0.15f);
        CHECK(image(x, y) <= 0.9f);
      }
      ++checked;
    }
  CHECK(checked > 6000);
}

TEST_CASE("synth: ground-truth points lie on the first surface along the ray") {
  for (const char* kind : {"urban", "indoor"}) {
    SynthConfig cfg = smallConfig(96, 1);
    cfg.scene = kind;
    cfg.seed = 11;
    cfg.nearest = 0.8;
    const SynthPair p = renderPair(cfg);
    const DepthCheck left = checkDepth(p.scene, p.rig.cam0, p.pose0, p.depthLeft, 3);
    const DepthCheck right = checkDepth(p.scene, p.rig.cam1, p.pose1, p.depthRight, 3);
    INFO(kind);
    CHECK(left.checked > 500);
    CHECK(left.worstOffSurface < 1e-6);
    CHECK(right.worstOffSurface < 1e-6);
    // Sphere tracing may stall on rays that graze an edge; almost all must agree.
    CHECK(left.agreeing >= 0.99 * left.checked);
    CHECK(right.agreeing >= 0.99 * right.checked);

    // The nearest object sits at the requested distance and nothing is nearer.
    float nearestDepth = std::numeric_limits<float>::infinity();
    for (float d : p.depthLeft.data)
      if (d > 0.f) nearestDepth = std::min(nearestDepth, d);
    CHECK(nearestDepth >= 0.8f * (1 - 1e-6f));
    bool foundNear = false;
    for (const Shape& s : p.scene.shapes())
      if (s.name == "near0") {
        foundNear = true;
        CHECK(signedDistance(s, p.pose0.centre) == doctest::Approx(0.8).epsilon(1e-9));
      }
    CHECK(foundNear);
  }
}

TEST_CASE("synth: sky is +inf and bright, outside the image circle is 0") {
  SynthConfig cfg = smallConfig(96, 2);
  cfg.seed = 3;
  const SynthPair p = renderPair(cfg);
  const double c = 0.5 * (96 - 1), radius = 48.0;
  const BuiltCamera cam0(p.rig.cam0);
  int sky = 0, surface = 0;
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x) {
      const float d = p.depthLeft(x, y), v = p.left(x, y);
      REQUIRE(!std::isnan(d));
      const double r = std::hypot(x - c, y - c);
      if (r > radius + 1e-9) {
        CHECK(d == 0.f);
        CHECK(v == 0.f);
        continue;
      }
      if (r < radius - 1.0) CHECK(d > 0.f);
      if (std::isinf(d)) {
        ++sky;
        // The ground reaches 100 m, so a sky ray points at most slightly downwards.
        CHECK((p.pose0.rotation * pixelRay(cam0, x, y)).z() > -0.03);
        if (r < radius - 1.5 && skyAround(p.depthLeft, x, y)) CHECK(std::abs(v - 0.93) < 0.08);
      } else if (d > 0.f) {
        ++surface;
      }
    }
  CHECK(sky > 50);
  CHECK(surface > 3000);
}

TEST_CASE("synth: the right view agrees with the left through depth, pose and models") {
  SUBCASE("binocular equidistant") {
    SynthConfig cfg = smallConfig(128, 2);
    cfg.rotationDeg = 2.0;
    const Consistency c = viewConsistency(renderPair(cfg));
    checkConsistency(c);
  }
  SUBCASE("forward motion, indoor") {
    SynthConfig cfg = smallConfig(128, 2);
    cfg.scene = "indoor";
    cfg.motion = "forward";
    cfg.baseline = 0.4;
    const Consistency c = viewConsistency(renderPair(cfg));
    checkConsistency(c);
  }
  SUBCASE("double sphere, model's own field of view (> 180 deg)") {
    SynthConfig cfg = smallConfig(128, 2);
    cfg.camera = doubleSphere195(128);
    cfg.maxFovDeg = 0;
    const SynthPair p = renderPair(cfg);
    const Consistency c = viewConsistency(p);
    checkConsistency(c);
    const DepthCheck d = checkDepth(p.scene, p.rig.cam0, p.pose0, p.depthLeft, 3);
    CHECK(d.worstOffSurface < 1e-6);
    CHECK(d.agreeing >= 0.99 * d.checked);
  }
}

TEST_CASE("synth: fields of view beyond 180 degrees render behind the image plane") {
  SynthConfig cfg = smallConfig(96, 1);
  cfg.camera = fisheye220(96);
  cfg.maxFovDeg = 220;
  const SynthPair wide = renderPair(cfg);
  int behind = 0;
  const BuiltCamera wide0(wide.rig.cam0);
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x) {
      if (!(wide.depthLeft(x, y) > 0.f)) continue;
      if (pixelRay(wide0, x, y).z() < -0.1) ++behind;
    }
  CHECK(behind > 200);
  const DepthCheck d = checkDepth(wide.scene, wide.rig.cam0, wide.pose0, wide.depthLeft, 2);
  CHECK(d.agreeing >= 0.99 * d.checked);

  // The same lens cut to 180 deg keeps only the front hemisphere.
  cfg.maxFovDeg = 180;
  const SynthPair cut = renderPair(cfg);
  CHECK(countValid(cut.depthLeft) < countValid(wide.depthLeft));
  const BuiltCamera cut0(cut.rig.cam0);
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x)
      if (cut.depthLeft(x, y) > 0.f) CHECK(pixelRay(cut0, x, y).z() >= -1e-9);
}

TEST_CASE("synth: supersampling keeps the image centred on the model's pixel centres") {
  // More samples change the image only by anti-aliasing, never by a shift: the mean
  // difference between 1 and 4 samples per axis is small next to the texture contrast.
  SynthConfig cfg = smallConfig(96, 1);
  const SynthPair one = renderPair(cfg);
  cfg.samplesPerAxis = 4;
  const SynthPair four = renderPair(cfg);
  CHECK(one.depthLeft.data == four.depthLeft.data);  // depth always from the centre ray
  double diff = 0.0, contrast = 0.0;
  int n = 0;
  for (int y = 1; y < 95; ++y)
    for (int x = 1; x < 95; ++x) {
      if (!(one.depthLeft(x, y) > 0.f) || !(one.depthLeft(x + 1, y) > 0.f)) continue;
      diff += std::abs(one.left(x, y) - four.left(x, y));
      contrast += std::abs(one.left(x + 1, y) - one.left(x, y));
      ++n;
    }
  CHECK(n > 4000);
  CHECK(diff < 0.5 * contrast);
}

// ---------------------------------------------------------------- sequences

namespace {

namespace fs = std::filesystem;

SequenceConfig tinySequence(int frames, int size) {
  SequenceConfig seq;
  seq.render.camera = defaultFisheye(size);
  seq.render.samplesPerAxis = 1;
  seq.frames = frames;
  return seq;
}

std::vector<std::string> dataLines(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

struct TimedPose {
  int64_t t = 0;
  Pose pose;  // T_world_cam0
};

// poses_cam0.csv: "t,px,py,pz,qx,qy,qz,qw" after a '#' header.
std::vector<TimedPose> readPoses(const fs::path& file) {
  std::vector<TimedPose> poses;
  for (const std::string& line : dataLines(file)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    std::string field;
    std::vector<double> v;
    TimedPose p;
    std::getline(in, field, ',');
    p.t = std::stoll(field);
    while (std::getline(in, field, ',')) v.push_back(std::stod(field));
    REQUIRE(v.size() == 7);
    p.pose.centre = Vector3d(v[0], v[1], v[2]);
    p.pose.rotation = Eigen::Quaterniond(v[6], v[3], v[4], v[5]).normalized().toRotationMatrix();
    poses.push_back(p);
  }
  return poses;
}

// Bilinear depth at (x, y) when its four pixels are finite surface depths within 5 % of
// each other (no edge, no sky); else 0.
double smoothDepthAt(const ImageF& depth, double x, double y) {
  const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  float lo = std::numeric_limits<float>::infinity(), hi = 0.f;
  for (int dy = 0; dy <= 1; ++dy)
    for (int dx = 0; dx <= 1; ++dx) {
      if (!depth.inside(x0 + dx, y0 + dy)) return 0.0;
      const float d = depth(x0 + dx, y0 + dy);
      if (!(d > 0.f) || std::isinf(d)) return 0.0;
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  return hi < 1.05f * lo ? bilinear(depth, x, y) : 0.0;
}

// Reprojects the surface pixels of depth a (camera pose a) into the camera of pose b and
// compares the predicted radial distance with depth b there. Returns the share that agrees
// within 1 % among those both see without an edge (count: how many were compared).
double reprojectedAgreement(const Camera& camA, const Pose& a, const ImageF& depthA, const ImageF& maskA,
                            const Camera& camB, const Pose& b, const ImageF& depthB, const ImageF& maskB, int& count) {
  const BuiltCamera builtA(camA), builtB(camB);
  int agree = 0;
  count = 0;
  for (int y = 0; y < depthA.height; ++y)
    for (int x = 0; x < depthA.width; ++x) {
      if (!maskA.empty() && maskA(x, y) > 0.f) continue;  // the mover moves
      const double d = smoothDepthAt(depthA, x, y);
      if (!(d > 0.0)) continue;
      const Vector3d ray = pixelRay(builtA, x, y);
      if (ray.z() < kRimCosine) continue;
      const Vector3d world = a.centre + a.rotation * (d * ray);
      const Vector3d inB = b.rotation.transpose() * (world - b.centre);
      Vec2<double> px;
      if (inB.normalized().z() < kRimCosine || !builtB.project(Vec3<double>(inB), px) || !builtB.inImage(px, 2.0))
        continue;
      if (!maskB.empty() && maskB(int(std::lround(px.x())), int(std::lround(px.y()))) > 0.f) continue;
      const double dB = smoothDepthAt(depthB, px.x(), px.y());
      if (!(dB > 0.0)) continue;
      ++count;
      agree += std::abs(dB - inB.norm()) < 0.01 * inB.norm();
    }
  return count ? double(agree) / count : 0.0;
}

// The eight corners of a box shape (world).
std::vector<Vector3d> boxCorners(const Shape& box) {
  std::vector<Vector3d> corners;
  for (int i = 0; i < 8; ++i) {
    const Vector3d local((i & 1 ? 1 : -1) * box.halfSize.x(), (i & 2 ? 1 : -1) * box.halfSize.y(),
                         (i & 4 ? 1 : -1) * box.halfSize.z());
    corners.push_back(box.centre + Vector3d(box.cosYaw * local.x() - box.sinYaw * local.y(),
                                            box.sinYaw * local.x() + box.cosYaw * local.y(), local.z()));
  }
  return corners;
}

}  // namespace

TEST_CASE("synth sequence: every file of the ASL layout, timestamps and the walk") {
  const fs::path dir = cs::test::tempDir("synth_sequence_files");
  SequenceConfig seq = tinySequence(3, 64);
  const SequenceRenderer renderer(seq);
  int reported = 0;
  SequenceCallbacks callbacks;
  callbacks.frameDone = [&](const SequenceFrameReport& r) { CHECK(r.index == reported++); };
  const SequenceReport report = writeSequence(renderer, CameraPhotometry(), dir.string(), callbacks);
  CHECK(reported == 3);
  CHECK(report.frames == 3);

  const std::vector<int64_t> stamps = {1000000000000, 1000033333333, 1000066666667};
  for (int k = 0; k < 3; ++k) CHECK(sequenceTimestampNs(k, 30.0) == stamps[size_t(k)]);
  CHECK(sequenceTimestampNs(14, 30.0) == 1000466666667);  // rounded, not truncated
  for (const char* stream : {"cam0", "cam1", "depth0", "depth1", "mover0", "mover1"}) {
    INFO(stream);
    const std::string ext = std::string(stream).compare(0, 5, "depth") == 0 ? ".exr" : ".png";
    const std::vector<std::string> lines = dataLines(dir / "mav0" / stream / "data.csv");
    REQUIRE(lines.size() == 4);
    CHECK(lines[0] == "#timestamp [ns],filename");
    for (int k = 0; k < 3; ++k) {
      const std::string name = std::to_string(stamps[size_t(k)]) + ext;
      CHECK(lines[size_t(k) + 1] == std::to_string(stamps[size_t(k)]) + "," + name);
      CHECK(fs::is_regular_file(dir / "mav0" / stream / "data" / name));
    }
  }
  for (const char* file : {"mav0/cam0/sensor.yaml", "mav0/cam1/sensor.yaml", "camchain.yaml", "meta.json"})
    CHECK(fs::is_regular_file(dir / file));
  CHECK(!fs::exists(dir / "photometry.json"));  // no camera model

  // Images and depth as the renderer made them; the mask is 0 / 255.
  const ImageF image = cs::readPngGray((dir / "mav0/cam1/data/1000033333333.png").string());
  CHECK(image.width == 64);
  const ImageF depth = cs::readExr((dir / "mav0/depth0/data/1000000000000.exr").string());
  const SequenceFrame frame0 = renderer.render(0);
  CHECK(depth.data == frame0.pair.depthLeft.data);
  const ImageF mask = cs::readPngGray((dir / "mav0/mover1/data/1000066666667.png").string());
  for (float v : mask.data) CHECK((v == 0.f || v == 1.f));

  // The camchain is the rig's; camera 1's sensor.yaml carries T_cam0_cam1.
  const cs::Rig rig = cs::loadKalibr((dir / "camchain.yaml").string());
  CHECK((rig.t - renderer.rig().t).norm() < 1e-12);
  CHECK(cs::test::readFile(dir / "mav0/cam1/sensor.yaml").find("data: [1, 0, 0, 0.12,") != std::string::npos);

  // Poses: T_world_cam0; frame 1 is speed / fps further along camera 0's z (plus the bob,
  // along its y), turned by turn / fps about the world vertical, to the left.
  const std::vector<TimedPose> poses = readPoses(dir / "poses_cam0.csv");
  REQUIRE(poses.size() == 3);
  for (int k = 0; k < 3; ++k) {
    CHECK(poses[size_t(k)].t == stamps[size_t(k)]);
    CHECK((poses[size_t(k)].pose.centre - renderer.pose0(k).centre).norm() < 1e-12);
    CHECK((poses[size_t(k)].pose.rotation - renderer.pose0(k).rotation).norm() < 1e-12);
  }
  CHECK((poses[0].pose.centre - renderer.staticScene().viewpoint.centre).norm() < 1e-12);
  const Pose &p0 = poses[0].pose, &p1 = poses[1].pose;
  const Vector3d step = p0.rotation.transpose() * (p1.centre - p0.centre);
  CHECK(step.z() == doctest::Approx(seq.speed / seq.fps).epsilon(1e-6));
  CHECK(std::abs(step.x()) < 1e-5);  // the bob of frame 1 is along its own (turned) y axis
  CHECK(std::abs(step.y()) <= seq.bobM);
  const Vector3d forward0 = p0.rotation.col(2), forward1 = p1.rotation.col(2);
  const double turned = std::atan2(forward0.x() * forward1.y() - forward0.y() * forward1.x(),
                                   forward0.x() * forward1.x() + forward0.y() * forward1.y());
  CHECK(turned * 180.0 / kPi == doctest::Approx(seq.turnDegPerS / seq.fps).epsilon(1e-9));  // > 0: left
  CHECK(std::abs(p1.rotation.col(2).z() - p0.rotation.col(2).z()) < 1e-12);                 // no pitch change
  CHECK(report.pathLength == doctest::Approx(2.0 * seq.speed / seq.fps).epsilon(0.05));
}

TEST_CASE("synth sequence: the mover is in both depth maps and exactly in its masks") {
  SequenceConfig seq = tinySequence(3, 64);
  seq.render.scene = "indoor";
  seq.render.seed = 4;
  const SequenceRenderer renderer(seq);
  REQUIRE(renderer.mover());
  const Mover& mover = *renderer.mover();
  CHECK(mover.halfSize.minCoeff() >= 0.15);
  CHECK(mover.halfSize.maxCoeff() <= 0.2);
  CHECK(mover.velocity.norm() == doctest::Approx(1.0).epsilon(0.1));
  CHECK(mover.velocity.z() == 0.0);
  int seen[2] = {0, 0};
  for (int k = 0; k < 3; ++k) {
    const SequenceFrame f = renderer.render(k);
    const Shape box = mover.shapeAt(renderer.seconds(k));
    CHECK(box.centre.z() == doctest::Approx(box.halfSize.z()));  // on the ground
    const ImageF* depths[2] = {&f.pair.depthLeft, &f.pair.depthRight};
    const ImageF* masks[2] = {&f.moverLeft, &f.moverRight};
    const Pose poses[2] = {f.pair.pose0, f.pair.pose1};
    const Camera cams[2] = {f.pair.rig.cam0, f.pair.rig.cam1};
    for (int c = 0; c < 2; ++c) {
      const BuiltCamera cam(cams[c]);
      const double nearest = signedDistance(box, poses[c].centre);
      double farthest = 0.0;
      for (const Vector3d& corner : boxCorners(box)) farthest = std::max(farthest, (corner - poses[c].centre).norm());
      CHECK(nearest > 1.5);
      CHECK(nearest < 3.0);
      int pixels = 0;
      for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
          const double d = (*depths[c])(x, y);
          const Vector3d point = poses[c].centre + d * (poses[c].rotation * pixelRay(cam, x, y));
          const bool onBox = d > 0.0 && std::isfinite(d) && std::abs(signedDistance(box, point)) < 1e-5 * d;
          if ((*masks[c])(x, y) > 0.f) {
            ++pixels;
            CHECK(d >= nearest * (1 - 1e-6));
            CHECK(d <= farthest * (1 + 1e-6));
            CHECK(onBox);
          } else {
            CHECK(!onBox);  // every pixel whose depth lies on the mover is in the mask
          }
        }
      if (pixels > 0) ++seen[c];
    }
  }
  CHECK(seen[0] >= 1);
  CHECK(seen[1] >= 1);

  // Without the mover: no masks, no mover folders.
  seq.mover = false;
  const SequenceRenderer still(seq);
  CHECK(!still.mover());
  CHECK(still.render(0).moverLeft.empty());
  const fs::path dir = cs::test::tempDir("synth_sequence_still");
  seq.frames = 1;
  writeSequence(SequenceRenderer(seq), CameraPhotometry(), dir.string());
  CHECK(fs::is_regular_file(dir / "mav0/depth1/data.csv"));
  CHECK(!fs::exists(dir / "mav0/mover0"));
}

TEST_CASE("synth sequence: static depth agrees across frames through the written poses") {
  // A large step (0.3 m, 9 deg) so that a wrong pose convention cannot pass.
  const fs::path dir = cs::test::tempDir("synth_sequence_reproject");
  SequenceConfig seq = tinySequence(2, 96);
  seq.render.scene = "indoor";
  seq.render.seed = 7;
  seq.fps = 10.0;
  seq.speed = 3.0;
  seq.turnDegPerS = 90.0;
  writeSequence(SequenceRenderer(seq), photometryProfile("t265"), dir.string());
  const std::vector<TimedPose> poses = readPoses(dir / "poses_cam0.csv");
  REQUIRE(poses.size() == 2);
  const cs::Rig rig = cs::loadKalibr((dir / "camchain.yaml").string());
  auto read = [&](const char* stream, int k, const char* ext) {
    const std::string file = (dir / "mav0" / stream / "data" / (std::to_string(poses[size_t(k)].t) + ext)).string();
    return std::string(ext) == ".exr" ? cs::readExr(file) : cs::readPngGray(file);
  };
  const ImageF depth0 = read("depth0", 0, ".exr"), depth1 = read("depth0", 1, ".exr");
  const ImageF mask0 = read("mover0", 0, ".png"), mask1 = read("mover0", 1, ".png");
  int count = 0;
  const double agree =
      reprojectedAgreement(rig.cam0, poses[0].pose, depth0, mask0, rig.cam0, poses[1].pose, depth1, mask1, count);
  INFO("camera 0, frame 0 -> 1: " << agree << " of " << count);
  CHECK(count > 2000);
  CHECK(agree > 0.97);

  // Camera 1 of frame 1 from camera 0 of frame 0: T_world_cam1 = T_world_cam0 inv(T_cn_cnm1).
  Pose cam1;
  cam1.rotation = poses[1].pose.rotation * rig.R.transpose();
  cam1.centre = poses[1].pose.centre - poses[1].pose.rotation * rig.R.transpose() * rig.t;
  const ImageF depthRight = read("depth1", 1, ".exr"), maskRight = read("mover1", 1, ".png");
  const double agreeRight =
      reprojectedAgreement(rig.cam0, poses[0].pose, depth0, mask0, rig.cam1, cam1, depthRight, maskRight, count);
  INFO("camera 0 frame 0 -> camera 1 frame 1: " << agreeRight << " of " << count);
  CHECK(count > 2000);
  CHECK(agreeRight > 0.97);

  // The camera model's images: 8-bit, noisy, the same exposure in both frames.
  CHECK(fs::is_regular_file(dir / "photometry.json"));
  const ImageF left0 = read("cam0", 0, ".png"), left1 = read("cam0", 1, ".png");
  double mean0 = 0.0, mean1 = 0.0;
  for (size_t i = 0; i < left0.size(); ++i) {
    mean0 += left0.data[i];
    mean1 += left1.data[i];
  }
  CHECK(mean1 == doctest::Approx(mean0).epsilon(0.15));
}

TEST_CASE("synth sequence: bad settings are refused in one line") {
  SequenceConfig seq = tinySequence(3, 32);
  seq.frames = 0;
  CHECK_THROWS_WITH_AS(seq.validate(), "synth: --frames must be 1..100000, got 0", cs::Error);
  seq.frames = 3;
  seq.fps = 0.0;
  CHECK_THROWS_AS(SequenceRenderer{seq}, cs::Error);
  seq.fps = 30.0;
  seq.speed = -1.0;
  CHECK_THROWS_AS(SequenceRenderer{seq}, cs::Error);
  // A walk straight through the buildings is refused before anything is rendered.
  seq.speed = 40.0;
  seq.frames = 200;
  CHECK_THROWS_WITH_AS(SequenceRenderer{seq}, doctest::Contains("the walk runs into the scene"), cs::Error);

  // The command line.
  const fs::path dir = cs::test::tempDir("synth_sequence_cli");
  const cs::test::CliOutcome ok = cs::test::runCli(dir, "synth --sequence -o seq --frames 2 --size 32 --samples 1");
  INFO(ok.err);
  CHECK(ok.exitCode == 0);
  CHECK(ok.out.find("rendered 2 frames") != std::string::npos);
  CHECK(fs::is_regular_file(dir / "seq/mav0/mover1/data/1000033333333.png"));
  CHECK(dataLines(dir / "seq/poses_cam0.csv").size() == 3);
  for (const char* args :
       {"synth --sequence -o seq --frames 0", "synth --sequence -o seq --mover maybe", "synth -o seq --frames 3",
        "synth --sequence -o seq --fps -30", "synth --sequence=yes -o seq"}) {
    const cs::test::CliOutcome bad = cs::test::runCli(dir, args);
    INFO(args << ": " << bad.err);
    CHECK(bad.exitCode != 0);
    CHECK(bad.err.find("error: ") != std::string::npos);
    CHECK(std::count(bad.err.begin(), bad.err.end(), '\n') == 1);
  }
}

TEST_CASE("a rig's scene surrounds it: the street closed behind, a near object in every camera's view") {
  const cs::synth::RigLayout layout = cs::synth::rigLayout("ring4", 64);
  cs::synth::SceneSpec spec;
  spec.nearest = 1.0;
  for (const cs::BodyPose& pose : layout.rig.poses) spec.rigCameras.push_back({pose.R, pose.p});
  const cs::synth::Scene scene = cs::synth::buildScene(spec);
  const cs::synth::Pose& body = scene.viewpoint;
  auto find = [&](const std::string& name) -> const cs::synth::Shape* {
    for (const cs::synth::Shape& shape : scene.shapes())
      if (shape.name == name) return &shape;
    return nullptr;
  };
  for (int k = 1; k < 4; ++k) {
    const cs::BodyPose& pose = layout.rig.poses[size_t(k)];
    const Vector3d centre = body.centre + body.rotation * pose.p, axis = body.rotation * pose.R.col(2);
    const cs::synth::Shape* near = find("near_cam" + std::to_string(k));
    CAPTURE(k);
    REQUIRE(near != nullptr);
    const double distance = cs::synth::signedDistance(*near, centre);
    CHECK(distance >= 1.0 - 1e-9);
    CHECK(distance <= 1.6 + 1e-9);
    CHECK((near->centre - centre).normalized().dot(axis) > std::cos(60.0 * M_PI / 180.0));  // in its view
  }
  // The street's far end ahead of the body (bld_end, world +y) has a counterpart behind it.
  const cs::synth::Shape* back = find("bld_back");
  REQUIRE(back != nullptr);
  CHECK(back->centre.y() < body.centre.y() - 15.0);
  // A pair's scene of the same seed has none of it.
  cs::synth::SceneSpec pair;
  pair.nearest = 1.0;
  const cs::synth::Scene pairScene = cs::synth::buildScene(pair);
  for (const cs::synth::Shape& shape : pairScene.shapes()) {
    CHECK(shape.name.rfind("near_cam", 0) == std::string::npos);
    CHECK(shape.name != "bld_back");
  }
}

// Procedural scene generation: a street between rows of buildings ("urban") or a
// furnished room with windows ("indoor"), plus a few objects close to camera 0.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "synth/random.hpp"
#include "synth/scene.hpp"

namespace cs::synth {
namespace {

using Eigen::Vector3d;

double degrees(double deg) { return deg * M_PI / 180.0; }

constexpr double kGroundRadius = 100.0;  // metres

// Camera axes (x right, y down, z forward) for a camera looking along world +y, level,
// turned by yaw about world z and tilted up by pitch.
Eigen::Matrix3d cameraRotation(double yaw, double pitch) {
  Eigen::Matrix3d level;
  level.col(0) = Vector3d::UnitX();
  level.col(1) = -Vector3d::UnitZ();
  level.col(2) = Vector3d::UnitY();
  // Positive rotation about the camera's x axis turns its z axis towards -y (up).
  return Eigen::AngleAxisd(yaw, Vector3d::UnitZ()).toRotationMatrix() * level *
         Eigen::AngleAxisd(pitch, Vector3d::UnitX()).toRotationMatrix();
}

// Note on determinism: C++ leaves the evaluation order of function arguments open, so
// no call below takes two random draws as arguments; draws go to named locals first
// (declarations and braced initialisers are evaluated in order).
class Builder {
 public:
  explicit Builder(const SceneSpec& spec) : spec_(spec), random_(spec.seed) {}

  Scene build() {
    if (spec_.kind == "urban") {
      buildUrban();
    } else if (spec_.kind == "indoor") {
      buildIndoor();
    } else {
      throw Error("unknown scene kind '" + spec_.kind + "' (expected urban or indoor)");
    }
    if (!spec_.rigCameras.empty()) addSurround();
    scene_.setDetail(scene_.viewpoint.centre, spec_.pixelAngle);
    return std::move(scene_);
  }

 private:
  const SceneSpec& spec_;
  Random random_;
  Scene scene_;
  std::vector<Vector3d> cameras_;      // world centres of all cameras
  std::vector<Eigen::Matrix3d> axes_;  // their camera-to-world rotations (known for a rig)
  double streetHalf_ = 0.0;            // urban: half the street's width

  void placeCameras(const Vector3d& centre0, double yaw, double pitch) {
    scene_.viewpoint.centre = centre0;
    scene_.viewpoint.rotation = cameraRotation(yaw, pitch);
    const Eigen::Matrix3d& R = scene_.viewpoint.rotation;
    if (!spec_.rigCameras.empty()) {  // the viewpoint is the rig's body
      cameras_.clear(), axes_.clear();
      for (const Pose& cam : spec_.rigCameras) {
        cameras_.push_back(centre0 + R * cam.centre);
        axes_.push_back(R * cam.rotation);
      }
      return;
    }
    cameras_ = {centre0};
    for (const Vector3d& c : spec_.otherCentresInCam0) cameras_.push_back(centre0 + R * c);
    axes_ = {R};
  }

  // z = 0 out to a finite horizon around camera 0: beyond it the sky, as in the dev
  // data (whose ground ends ~90 m away), instead of depths of kilometres.
  Shape groundPlane(const std::string& name) {
    const Vector3d foot(scene_.viewpoint.centre.x(), scene_.viewpoint.centre.y(), 0.0);
    return makePlane(foot, Vector3d::UnitZ(), material(0.2), name, kGroundRadius);
  }

  void chooseLight(double minElevationDeg, double maxElevationDeg) {
    const double elevation = degrees(random_.uniform(minElevationDeg, maxElevationDeg));
    const double azimuth = random_.uniform(0.0, 2.0 * M_PI);
    scene_.lightDir =
        Vector3d(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
  }

  Material material(double patternScale) { return randomMaterial(random_, patternScale); }
  // Three draws, in order.
  Vector3d uniform3(double lo, double hi) {
    const double x = random_.uniform(lo, hi), y = random_.uniform(lo, hi), z = random_.uniform(lo, hi);
    return Vector3d(x, y, z);
  }

  double clearanceOf(const Shape& shape) const {
    double nearest = std::numeric_limits<double>::infinity();
    for (const Vector3d& c : cameras_) nearest = std::min(nearest, signedDistance(shape, c));
    return nearest;
  }

  // Clutter keeps clear of every camera so that the designated near objects stay the
  // nearest and no camera ends up inside a solid. Gives up after a few proposals.
  template <class Propose>
  void addClutter(int count, Propose propose) {
    const double clearance = 1.5 * spec_.nearest;
    for (int i = 0; i < count; ++i)
      for (int attempt = 0; attempt < 20; ++attempt) {
        Shape shape = propose(i);
        if (clearanceOf(shape) >= clearance) {
          scene_.add(shape);
          break;
        }
      }
  }

  // Moves `shape` along dir until its distance from camera `cam` is exactly `distance`
  // (distance grows monotonically as a convex solid slides away along dir).
  void slideToDistance(Shape& shape, const Vector3d& dir, double distance, size_t cam) {
    for (int i = 0; i < 50; ++i) {
      const double error = distance - signedDistance(shape, cameras_[cam]);
      if (std::abs(error) < 1e-12 * distance) break;
      shape.centre += error * dir;
    }
  }

  // A direction in a camera's view (axes: camera-to-world), 20-55 deg off axis, mostly beside
  // or below the axis (so the object stands in front of the camera rather than hanging above it).
  Vector3d nearDirection(const Eigen::Matrix3d& axes) {
    const double offAxis = degrees(random_.uniform(20.0, 55.0));
    const double around = degrees(random_.uniform(-30.0, 210.0));  // image angle, y down
    const Vector3d inCamera(std::sin(offAxis) * std::cos(around), std::sin(offAxis) * std::sin(around),
                            std::cos(offAxis));
    return axes * inCamera;
  }

  Shape nearShape(bool box, const std::string& name) {
    const double n = spec_.nearest;
    if (box) {
      const Vector3d size =
          n * Vector3d{random_.uniform(0.12, 0.3), random_.uniform(0.12, 0.3), random_.uniform(0.2, 0.5)};
      const double yaw = random_.uniform(0.0, M_PI);
      return makeBox(Vector3d::Zero(), size, yaw, material(0.08 * n), name);
    }
    const double radius = n * random_.uniform(0.08, 0.18), height = n * random_.uniform(0.8, 1.6);
    return makeCylinder(Vector3d::Zero(), radius, height, material(0.08 * n), name);
  }

  // A near object `distance` from camera `cam`, in its view.
  void addNearObject(bool box, double distance, const std::string& name, size_t cam = 0) {
    const double n = spec_.nearest;
    for (int attempt = 0; attempt < 100; ++attempt) {
      const Vector3d dir = nearDirection(axes_[cam]);
      Shape shape = nearShape(box, name);
      shape.centre = cameras_[cam] + dir * (distance + shape.halfSize.maxCoeff());
      slideToDistance(shape, dir, distance, cam);
      bool clearOfOthers = true;  // another camera may be nearer, but never inside or grazing it
      for (size_t c = 0; c < cameras_.size(); ++c)
        if (c != cam) clearOfOthers &= signedDistance(shape, cameras_[c]) > 0.4 * n;
      if (clearOfOthers) {
        scene_.add(shape);
        return;
      }
    }
  }

  void addNearObjects() {
    addNearObject(true, spec_.nearest, "near0");
    addNearObject(false, spec_.nearest * random_.uniform(1.15, 1.7), "near1");
  }

  // A wall slab from a to b (ground plan, z from 0 to height) with an optional window.
  void addWall(double x0, double y0, double x1, double y1, double height, double thickness, bool window,
               const Material& m, const std::string& name) {
    const Vector3d along(x1 - x0, y1 - y0, 0.0);
    const double length = along.norm(), yaw = std::atan2(along.y(), along.x());
    const Vector3d unit = along / length;
    auto piece = [&](double s0, double s1, double z0, double z1) {
      const Vector3d centre = Vector3d(x0, y0, 0.0) + unit * (0.5 * (s0 + s1)) + Vector3d(0, 0, 0.5 * (z0 + z1));
      scene_.add(makeBox(centre, Vector3d(0.5 * (s1 - s0), 0.5 * thickness, 0.5 * (z1 - z0)), yaw, m, name));
    };
    if (!window) {
      piece(0.0, length, 0.0, height);
      return;
    }
    const double width = random_.uniform(0.25, 0.45) * length;
    const double start = random_.uniform(0.1 * length, 0.9 * length - width);
    const double sill = random_.uniform(0.6, 1.0);
    const double top = height - random_.uniform(0.2, 0.5);
    piece(0.0, start, 0.0, height);
    piece(start + width, length, 0.0, height);
    piece(start, start + width, 0.0, sill);
    piece(start, start + width, top, height);
  }

  void buildUrban();
  void buildIndoor();
  void addSurround();
  void closeStreetBehind();
};

void Builder::buildUrban() {
  const double half = random_.uniform(4.0, 6.5);  // half width of the street
  streetHalf_ = half;
  const Vector3d centre0{random_.uniform(-0.4, 0.4) * half, 0.0, random_.uniform(1.3, 1.7)};
  const double cameraYaw = degrees(random_.uniform(-12.0, 12.0)), cameraPitch = degrees(random_.uniform(-6.0, 4.0));
  placeCameras(centre0, cameraYaw, cameraPitch);
  chooseLight(40.0, 70.0);

  scene_.add(groundPlane("ground"));
  for (int side : {-1, 1}) {
    const std::string tag = side < 0 ? "-" : "+";
    scene_.add(makeBox(Vector3d(side * (half - 1.0), 35.0, 0.075), Vector3d(1.0, 65.0, 0.075), 0.0, material(0.15),
                       "curb" + tag));
    int index = 0;
    for (double y = -30.0; y < 100.0; ++index) {
      const double length = random_.uniform(6.0, 16.0), depth = random_.uniform(6.0, 12.0),
                   height = random_.uniform(5.0, 25.0);
      const Vector3d centre(side * (half + 0.5 * depth), y + 0.5 * length, 0.5 * height);
      const double yaw = degrees(random_.uniform(-3.0, 3.0));
      const Material look = material(random_.uniform(0.3, 0.8));
      scene_.add(makeBox(centre, Vector3d(0.5 * depth, 0.5 * length, 0.5 * height), yaw, look,
                         "bld" + tag + std::to_string(index)));
      y += length + (random_.chance(0.3) ? random_.uniform(1.0, 4.0) : 0.0);
    }
  }
  const double endY = random_.uniform(55.0, 85.0), endHeight = random_.uniform(8.0, 25.0);
  scene_.add(makeBox(Vector3d(0.0, endY + 5.0, 0.5 * endHeight), Vector3d(half + 15.0, 5.0, 0.5 * endHeight), 0.0,
                     material(0.6), "bld_end"));

  auto streetPoint = [&](double margin) {
    return Vector3d{random_.uniform(-half + margin, half - margin), random_.uniform(-5.0, 45.0), 0.0};
  };
  addClutter(random_.integer(4, 7), [&](int i) {
    const Vector3d size = uniform3(0.2, 1.0), base = streetPoint(0.5);
    const double yaw = random_.uniform(0.0, M_PI);
    return makeBox(base + Vector3d(0, 0, size.z()), size, yaw, material(0.1), "box" + std::to_string(i));
  });
  addClutter(random_.integer(3, 5), [&](int i) {
    const double r = random_.uniform(0.2, 0.8), lift = random_.chance(0.3) ? random_.uniform(0.2, 1.5) : 0.0;
    const Vector3d base = streetPoint(0.5);
    return makeSphere(base + Vector3d(0, 0, r + lift), r, material(0.08), "sphere" + std::to_string(i));
  });
  addClutter(random_.integer(3, 5), [&](int i) {
    const Vector3d base = streetPoint(0.5);
    const double radius = random_.uniform(0.15, 0.5), height = random_.uniform(0.5, 2.5);
    return makeCylinder(base, radius, height, material(0.08), "cyl" + std::to_string(i));
  });
  addClutter(random_.integer(5, 9), [&](int i) {
    const Vector3d base = streetPoint(0.2);
    const double radius = random_.uniform(0.03, 0.08), height = random_.uniform(2.5, 5.0);
    return makeCylinder(base, radius, height, material(0.05), "pole" + std::to_string(i));
  });
  addNearObjects();
}

void Builder::buildIndoor() {
  const double width = random_.uniform(6.0, 9.0), length = random_.uniform(9.0, 14.0),
               roomHeight = random_.uniform(2.6, 3.2);
  const double x0 = -0.5 * width, x1 = 0.5 * width, y0 = -3.0, y1 = length - 3.0;
  const Vector3d centre0{random_.uniform(-0.25, 0.25) * width, random_.uniform(-1.0, 1.0), random_.uniform(1.2, 1.6)};
  const double cameraYaw = degrees(random_.uniform(-20.0, 20.0)), cameraPitch = degrees(random_.uniform(-8.0, 8.0));
  placeCameras(centre0, cameraYaw, cameraPitch);
  chooseLight(30.0, 70.0);

  // The floor is an infinite ground plane: through the windows it continues outside.
  scene_.add(groundPlane("floor"));
  const double t = 0.2;
  scene_.add(makeBox(Vector3d(0.0, 0.5 * (y0 + y1), roomHeight + 0.5 * t),
                     Vector3d(0.5 * width + t, 0.5 * length + t, 0.5 * t), 0.0, material(0.35), "ceiling"));
  const int windowWall = random_.integer(0, 1);
  const Material wallMaterial = material(0.3);
  addWall(x0 - 0.5 * t, y0 - t, x0 - 0.5 * t, y1 + t, roomHeight, t, windowWall == 0, wallMaterial, "wall_left");
  const Material rightMaterial = material(0.3), backMaterial = material(0.3), frontMaterial = material(0.3);
  addWall(x1 + 0.5 * t, y0 - t, x1 + 0.5 * t, y1 + t, roomHeight, t, windowWall == 1, rightMaterial, "wall_right");
  addWall(x0, y0 - 0.5 * t, x1, y0 - 0.5 * t, roomHeight, t, false, backMaterial, "wall_back");
  const bool frontWindow = random_.chance(0.5);
  addWall(x0, y1 + 0.5 * t, x1, y1 + 0.5 * t, roomHeight, t, frontWindow, frontMaterial, "wall_front");
  // Outside, seen through the windows.
  for (int i = 0; i < 4; ++i) {
    const double side = (i % 2 == 0) ? -1.0 : 1.0, h = random_.uniform(4.0, 15.0);
    const Vector3d centre{side * random_.uniform(15.0, 30.0), random_.uniform(-10.0, 30.0), 0.5 * h};
    const Vector3d size{random_.uniform(2.0, 5.0), random_.uniform(3.0, 8.0), 0.5 * h};
    scene_.add(makeBox(centre, size, 0.0, material(0.6), "outside" + std::to_string(i)));
  }

  auto floorPoint = [&](double margin) {
    return Vector3d{random_.uniform(x0 + margin, x1 - margin), random_.uniform(y0 + margin, y1 - margin), 0.0};
  };
  // Boxes standing on the floor: tables, then cabinets.
  auto furniture = [&](double lo, double hi, double marginToWall, const std::string& name) {
    return [&, lo, hi, marginToWall, name](int i) {
      const Vector3d size{random_.uniform(lo, hi), random_.uniform(0.5 * lo, 0.7 * hi), random_.uniform(0.35, 1.0)};
      const Vector3d base = floorPoint(marginToWall);
      const double yaw = random_.uniform(0.0, M_PI);
      return makeBox(base + Vector3d(0, 0, size.z()), size, yaw, material(0.08), name + std::to_string(i));
    };
  };
  addClutter(random_.integer(2, 4), furniture(0.4, 0.9, 0.8, "table"));
  addClutter(random_.integer(2, 4), furniture(0.3, 0.6, 0.5, "cabinet"));
  addClutter(random_.integer(1, 3), [&](int i) {
    const Vector3d base = floorPoint(0.5);
    const double radius = random_.uniform(0.12, 0.3);
    return makeCylinder(base, radius, roomHeight, material(0.1), "column" + std::to_string(i));
  });
  addClutter(random_.integer(1, 3), [&](int i) {
    const double r = random_.uniform(0.15, 0.4), lift = random_.uniform(0.0, 1.0);
    const Vector3d base = floorPoint(0.5);
    return makeSphere(base + Vector3d(0, 0, r + lift), r, material(0.06), "sphere" + std::to_string(i));
  });
  addClutter(random_.integer(2, 4), [&](int i) {
    const Vector3d base = floorPoint(0.3);
    const double radius = random_.uniform(0.02, 0.05), height = random_.uniform(1.0, 2.2);
    return makeCylinder(base, radius, height, material(0.04), "pole" + std::to_string(i));
  });
  addNearObjects();
}

// A rig looks all around: behind camera 0 the urban street gets an end of its own and some
// clutter (a pair's scene has both only ahead), and every other camera a near object in its
// view, so that each camera sees structure near and far.
void Builder::addSurround() {
  if (spec_.kind == "urban") closeStreetBehind();
  for (size_t cam = 1; cam < cameras_.size(); ++cam) {
    const double distance = spec_.nearest * random_.uniform(1.0, 1.6);
    addNearObject(cam % 2 == 1, distance, "near_cam" + std::to_string(cam), cam);
  }
}

void Builder::closeStreetBehind() {
  // The building rows start 30 m behind the street's origin: the end stands within them.
  const double half = streetHalf_;
  const double backY = -random_.uniform(18.0, 27.0), height = random_.uniform(8.0, 25.0);
  scene_.add(makeBox(Vector3d(0.0, backY - 5.0, 0.5 * height), Vector3d(half + 16.0, 5.0, 0.5 * height), 0.0,
                     material(0.6), "bld_back"));
  const double y0 = std::max(backY + 1.0, -15.0);
  auto behind = [&](double margin) {
    return Vector3d{random_.uniform(-half + margin, half - margin), random_.uniform(y0, -1.0), 0.0};
  };
  addClutter(random_.integer(3, 5), [&](int i) {
    const Vector3d size = uniform3(0.2, 1.0), base = behind(0.5);
    const double yaw = random_.uniform(0.0, M_PI);
    return makeBox(base + Vector3d(0, 0, size.z()), size, yaw, material(0.1), "box_back" + std::to_string(i));
  });
  addClutter(random_.integer(2, 4), [&](int i) {
    const Vector3d base = behind(0.2);
    const double radius = random_.uniform(0.03, 0.08), height = random_.uniform(2.5, 5.0);
    return makeCylinder(base, radius, height, material(0.05), "pole_back" + std::to_string(i));
  });
}

}  // namespace

Scene buildScene(const SceneSpec& spec) {
  if (!(spec.nearest > 0.0)) throw Error("synth: the nearest object distance must be positive");
  return Builder(spec).build();
}

}  // namespace cs::synth

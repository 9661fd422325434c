// Scene geometry: ray intersection, distance field and shading of the primitives.
#include "synth/scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cs::synth {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

// A box's frame differs from the world only by a rotation about z.
Vector3d toBoxFrame(const Shape& s, const Vector3d& v) {
  return Vector3d(s.cosYaw * v.x() + s.sinYaw * v.y(), -s.sinYaw * v.x() + s.cosYaw * v.y(), v.z());
}
Vector3d fromBoxFrame(const Shape& s, const Vector3d& v) {
  return Vector3d(s.cosYaw * v.x() - s.sinYaw * v.y(), s.sinYaw * v.x() + s.cosYaw * v.y(), v.z());
}

// Each intersector returns true for a hit with 0 < t < tMax and sets t and the outward
// normal. Ray origins are outside every solid (the generator keeps cameras clear).

bool intersectPlane(const Shape& s, const Ray& ray, double tMax, double& t, Vector3d& normal) {
  const double facing = s.normal.dot(ray.dir);
  if (std::abs(facing) < 1e-15) return false;
  const double tHit = s.normal.dot(s.centre - ray.origin) / facing;
  if (!(tHit > 0.0 && tHit < tMax)) return false;
  if (std::isfinite(s.extent) && (ray.origin + tHit * ray.dir - s.centre).squaredNorm() > s.extent * s.extent)
    return false;
  t = tHit;
  normal = s.normal;
  return true;
}

// Slab test in the box's own frame.
bool intersectBox(const Shape& s, const Ray& ray, double tMax, double& t, Vector3d& normal) {
  const Vector3d o = toBoxFrame(s, ray.origin - s.centre), d = toBoxFrame(s, ray.dir);
  double tNear = -std::numeric_limits<double>::infinity(), tFar = tMax;
  int nearAxis = -1;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (std::abs(o[a]) > s.halfSize[a]) return false;
      continue;
    }
    double t0 = (-s.halfSize[a] - o[a]) / d[a], t1 = (s.halfSize[a] - o[a]) / d[a];
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > tNear) {
      tNear = t0;
      nearAxis = a;
    }
    tFar = std::min(tFar, t1);
    if (tNear > tFar) return false;
  }
  if (nearAxis < 0 || !(tNear > 0.0)) return false;
  Vector3d local = Vector3d::Zero();
  local[nearAxis] = d[nearAxis] > 0.0 ? -1.0 : 1.0;
  t = tNear;
  normal = fromBoxFrame(s, local);
  return true;
}

bool intersectSphere(const Shape& s, const Ray& ray, double tMax, double& t, Vector3d& normal) {
  const Vector3d oc = ray.origin - s.centre;
  const double radius = s.halfSize.x();
  const double b = ray.dir.dot(oc), c = oc.squaredNorm() - radius * radius;
  const double disc = b * b - c;
  if (b >= 0.0 || disc < 0.0 || c <= 0.0) return false;
  // c / (-b + sqrt) equals -b - sqrt without cancellation for small, far spheres.
  const double tHit = c / (-b + std::sqrt(disc));
  if (!(tHit < tMax)) return false;
  t = tHit;
  normal = (oc + tHit * ray.dir) / radius;
  return true;
}

bool intersectCylinder(const Shape& s, const Ray& ray, double tMax, double& t, Vector3d& normal) {
  const Vector3d o = ray.origin - s.centre;
  const Vector3d& d = ray.dir;
  const double radius = s.halfSize.x(), halfHeight = s.halfSize.z();
  bool found = false;
  // Mantle: |o_xy + t d_xy| = radius, entering root only.
  const double a = d.x() * d.x() + d.y() * d.y();
  const double b = o.x() * d.x() + o.y() * d.y();
  const double c = o.x() * o.x() + o.y() * o.y() - radius * radius;
  const double disc = b * b - a * c;
  if (a > 0.0 && c > 0.0 && b < 0.0 && disc >= 0.0) {
    const double tHit = c / (-b + std::sqrt(disc));
    if (tHit < tMax && std::abs(o.z() + tHit * d.z()) <= halfHeight) {
      t = tMax = tHit;
      const Vector3d p = o + tHit * d;
      normal = Vector3d(p.x(), p.y(), 0.0) / radius;
      found = true;
    }
  }
  // Caps: only the one facing the ray origin can be an entry point.
  if (d.z() != 0.0 && std::abs(o.z()) > halfHeight) {
    const double side = o.z() > 0.0 ? 1.0 : -1.0;
    const double tHit = (side * halfHeight - o.z()) / d.z();
    const double px = o.x() + tHit * d.x(), py = o.y() + tHit * d.y();
    if (tHit > 0.0 && tHit < tMax && px * px + py * py <= radius * radius) {
      t = tHit;
      normal = Vector3d(0.0, 0.0, side);
      found = true;
    }
  }
  return found;
}

bool intersectShape(const Shape& s, const Ray& ray, double tMax, double& t, Vector3d& normal) {
  switch (s.kind) {
    case ShapeKind::Plane:
      return intersectPlane(s, ray, tMax, t, normal);
    case ShapeKind::Box:
      return intersectBox(s, ray, tMax, t, normal);
    case ShapeKind::Sphere:
      return intersectSphere(s, ray, tMax, t, normal);
    case ShapeKind::Cylinder:
      return intersectCylinder(s, ray, tMax, t, normal);
  }
  return false;
}

}  // namespace

double signedDistance(const Shape& s, const Vector3d& p) {
  switch (s.kind) {
    case ShapeKind::Plane: {
      const Vector3d offset = p - s.centre;
      const double height = s.normal.dot(offset);
      const double beyondRim = (offset - height * s.normal).norm() - s.extent;  // in the plane
      if (!(beyondRim > 0.0)) return height;
      return std::copysign(std::hypot(beyondRim, height), height);
    }
    case ShapeKind::Sphere:
      return (p - s.centre).norm() - s.halfSize.x();
    case ShapeKind::Box: {
      const Vector3d q = toBoxFrame(s, p - s.centre).cwiseAbs() - s.halfSize;
      return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
    }
    case ShapeKind::Cylinder: {
      const Vector3d o = p - s.centre;
      const Vector2d q(std::hypot(o.x(), o.y()) - s.halfSize.x(), std::abs(o.z()) - s.halfSize.z());
      return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
    }
  }
  return std::numeric_limits<double>::infinity();
}

Shape makePlane(const Vector3d& point, const Vector3d& normal, const Material& m, const std::string& name,
                double extent) {
  Shape s;
  s.kind = ShapeKind::Plane;
  s.name = name;
  s.centre = point;
  s.normal = normal.normalized();
  s.extent = extent;
  s.material = m;
  return s;
}

Shape makeBox(const Vector3d& centre, const Vector3d& halfSize, double yawRad, const Material& m,
              const std::string& name) {
  Shape s;
  s.kind = ShapeKind::Box;
  s.name = name;
  s.centre = centre;
  s.halfSize = halfSize;
  s.cosYaw = std::cos(yawRad);
  s.sinYaw = std::sin(yawRad);
  s.material = m;
  return s;
}

Shape makeSphere(const Vector3d& centre, double radius, const Material& m, const std::string& name) {
  Shape s;
  s.kind = ShapeKind::Sphere;
  s.name = name;
  s.centre = centre;
  s.halfSize = Vector3d(radius, radius, radius);
  s.material = m;
  return s;
}

Shape makeCylinder(const Vector3d& base, double radius, double height, const Material& m, const std::string& name) {
  Shape s;
  s.kind = ShapeKind::Cylinder;
  s.name = name;
  s.centre = base + Vector3d(0.0, 0.0, 0.5 * height);
  s.halfSize = Vector3d(radius, radius, 0.5 * height);
  s.material = m;
  return s;
}

bool Scene::intersect(const Ray& ray, Hit& hit) const {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < shapes_.size(); ++i) {
    double t;
    Vector3d normal;
    if (intersectShape(shapes_[i], ray, best, t, normal)) {
      best = t;
      hit.normal = normal;
      hit.shape = int(i);
    }
  }
  if (!std::isfinite(best)) return false;
  hit.distance = best;
  hit.point = ray.origin + best * ray.dir;
  return true;
}

double Scene::radiance(const Hit& hit) const {
  const Shape& shape = shapes_[size_t(hit.shape)];
  // Footprint of a pixel seen from the detail anchor, widened on surfaces seen at a
  // grazing angle from there (a far ground plane) so they fade instead of aliasing.
  const Vector3d fromAnchor = hit.point - detailAnchor_;
  const double distance = std::max(fromAnchor.norm(), 1e-6);
  const double obliquity = std::max(std::abs(hit.normal.dot(fromAnchor)) / distance, 0.2);
  const double footprint = distance * pixelAngle_ / obliquity;
  const double albedo = textureAlbedo(shape.material, hit.point, footprint);
  // Lambertian-like shading from a fixed light: depends on the normal only, so faces
  // of a box differ in brightness but nothing depends on the viewer.
  const double shade = 0.7 + 0.3 * hit.normal.dot(lightDir);
  return 0.15 + 0.75 * albedo * shade;
}

double Scene::signedDistance(const Vector3d& p) const {
  double nearest = std::numeric_limits<double>::infinity();
  for (const Shape& s : shapes_) nearest = std::min(nearest, synth::signedDistance(s, p));
  return nearest;
}

void Scene::setDetail(const Vector3d& anchor, double pixelAngle) {
  detailAnchor_ = anchor;
  pixelAngle_ = pixelAngle;
}

}  // namespace cs::synth

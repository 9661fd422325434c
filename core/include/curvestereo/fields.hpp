// The per-rig fields of the method (docs/design.md "Per rig"), computed in double precision.
#pragma once
#include <Eigen/Core>

#include "curvestereo/camera.hpp"
#include "curvestereo/image.hpp"

namespace cs {

struct FieldOptions {
  double maxFovDeg = 0.0;   // 0: the camera model's own valid region
  double epipoleDeg = 3.0;  // mask rays closer than this to the baseline direction
};

struct RigFields {
  ImageU8 mask;           // 1 where the pixel takes part in the solve
  FlowImage calibration;  // c(x) = pi1(R pi0^-1(x)) - x
  FlowImage trajectory;   // unit tangent of the epipolar curve (towards decreasing depth)
};

struct PixelFields {
  bool valid = false;
  Vec2f calibration, trajectory;  // zero where not valid
};

// The fields of one pixel (x, y) of cam0 for X1 = R X0 + t (cameras built once, not per pixel).
PixelFields fieldsAtPixel(const BuiltCamera& cam0, const BuiltCamera& cam1, const Eigen::Matrix3d& R,
                          const Eigen::Vector3d& t, const FieldOptions& options, int x, int y);

// Fields on cam0's pixel grid for the relative pose X1 = R X0 + t. `cam0Grid` may be a
// scaled copy of cam0 (a pyramid level); cam1 is then scaled alike by the caller.
RigFields computeFields(const Camera& cam0, const Camera& cam1, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                        const FieldOptions& options);

}  // namespace cs

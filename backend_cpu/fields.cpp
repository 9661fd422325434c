// Per rig / per pose: the valid mask, calibration and trajectory fields, in double
// precision through the camera models (core/src/fields.cpp holds the per-pixel maths).
#include <Eigen/Core>

#include "cpu_backend.hpp"
#include "curvestereo/camera.hpp"
#include "curvestereo/fields.hpp"

namespace cs::cpu {

void fields(const View& mask, const View& calibration, const View& trajectory, const FieldsParams& p) {
  const BuiltCamera cam0(toCamera(p.cam0)), cam1(toCamera(p.cam1));
  const Eigen::Matrix3d R = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(p.R);
  const Eigen::Vector3d t(p.t[0], p.t[1], p.t[2]);
  const FieldOptions options{p.maxFovDeg, p.epipoleDeg};
  parallelRows(mask.height, [&](int y) {
    for (int x = 0; x < mask.width; ++x) {
      PixelFields f = fieldsAtPixel(cam0, cam1, R, t, options, x, y);
      bool valid = f.valid && mask.at(x, y) != 0.f;
      mask.at(x, y) = valid ? 1.f : 0.f;
      calibration.at(x, y, 0) = f.calibration.x;
      calibration.at(x, y, 1) = f.calibration.y;
      trajectory.at(x, y, 0) = f.trajectory.x;
      trajectory.at(x, y, 1) = f.trajectory.y;
    }
  });
}

}  // namespace cs::cpu

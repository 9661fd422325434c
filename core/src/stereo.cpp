#include "curvestereo/stereo.hpp"

#include <chrono>
#include <cmath>
#include <limits>

#include "curvestereo/backend.hpp"
#include "pipeline.hpp"

namespace cs {

namespace {

std::string sizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

void checkImage(const ImageF& img, const Camera& cam, const char* which) {
  if (img.width != cam.width || img.height != cam.height)
    throw Error(std::string(which) + " image is " + sizeText(img.width, img.height) + " but the calibration says " +
                sizeText(cam.width, cam.height));
  for (float v : img.data)
    if (!std::isfinite(v)) throw Error(std::string(which) + " image contains NaN or infinite pixels");
}

}  // namespace

Stereo::Stereo(const Rig& rig, const Params& params, const std::string& backend) : rig_(rig), params_(params) {
  rig_.validate();
  params_.validate();
  if (rig.cam0.width < 16 || rig.cam0.height < 16)
    throw Error("images of " + sizeText(rig.cam0.width, rig.cam0.height) + " are too small (at least 16x16)");
  if (rig.cam1.width != rig.cam0.width || rig.cam1.height != rig.cam0.height)
    throw Error("the cameras differ in resolution (" + sizeText(rig.cam0.width, rig.cam0.height) + " and " +
                sizeText(rig.cam1.width, rig.cam1.height) + "): both images must have the same size");
  backend_ = createBackend(backend, &backendWhy_);
  backendName_ = backend_->name();
  pipeline_ = std::make_unique<Pipeline>(*backend_, rig_, params_, userMask_);
  pipeline_->setPose(rig_.R, rig_.t);
}

Stereo::~Stereo() = default;

void Stereo::setPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Rig moved = rig_;
  moved.R = R;
  moved.t = t;
  moved.validate();
  rig_ = moved;
  pipeline_->setPose(R, t);
}

void Stereo::setMask(const ImageU8& mask) {
  if (mask.width != rig_.cam0.width || mask.height != rig_.cam0.height)
    throw Error("mask is " + sizeText(mask.width, mask.height) + " but the images are " +
                sizeText(rig_.cam0.width, rig_.cam0.height));
  userMask_ = mask;
  pipeline_ = std::make_unique<Pipeline>(*backend_, rig_, params_, userMask_);
  pipeline_->setPose(rig_.R, rig_.t);
}

void Stereo::setProgress(std::function<void(double)> progress) { progress_ = std::move(progress); }

const std::string& Stereo::backendName() const { return backendName_; }
std::string Stereo::deviceName() const { return backend_->device(); }

DepthResult Stereo::compute(const ImageF& left, const ImageF& right) {
  checkImage(left, rig_.cam0, "left");
  checkImage(right, rig_.cam1, "right");
  const auto t0 = std::chrono::steady_clock::now();
  Pipeline::Output out = pipeline_->run(left, right, profiling_, progress_);

  DepthResult r;
  r.valid = std::move(out.valid);
  r.disparity = std::move(out.disparity);
  r.warp = std::move(out.warp);
  r.depth.radial = std::move(out.radial);
  r.depth.points = std::move(out.points);
  r.depth.z = ImageF(r.valid.width, r.valid.height);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (size_t i = 0; i < r.valid.size(); ++i) {
    // A non-finite solution would be a solver failure: report the pixel as unsolved
    // rather than pass a NaN on as if it were depth.
    const bool finite =
        std::isfinite(r.disparity.data[i]) && std::isfinite(r.warp.data[i].x) && std::isfinite(r.warp.data[i].y);
    if (!finite || !r.valid.data[i]) {
      r.valid.data[i] = 0;
      r.disparity.data[i] = nan;
      r.warp.data[i] = {nan, nan};
      r.depth.radial.data[i] = nan;
      r.depth.points.data[i] = {nan, nan, nan};
    }
    // A point at infinity has infinite z too (reported as +inf, also beyond 90 degrees).
    const float radial = r.depth.radial.data[i];
    r.depth.z.data[i] = std::isinf(radial) ? radial : r.depth.points.data[i].z;
  }
  r.stages = std::move(out.stages);
  r.totalMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace cs

#include "curvestereo/stereo.hpp"

#include <chrono>
#include <cmath>
#include <limits>

#include "curvestereo/backend.hpp"
#include "pipeline.hpp"

namespace cs {

namespace {

void checkImage(const ImageF& img, const Camera& cam, const char* which) {
  if (img.width != cam.width || img.height != cam.height)
    throw Error(std::string(which) + " image is " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                " but the calibration says " + std::to_string(cam.width) + "x" + std::to_string(cam.height));
  for (float v : img.data)
    if (!std::isfinite(v)) throw Error(std::string(which) + " image contains NaN or infinite pixels");
}

}  // namespace

Stereo::Stereo(const Rig& rig, const Params& params, const std::string& backend) : rig_(rig), params_(params) {
  rig_.validate();
  params_.validate();
  if (pyramidPlan(rig.cam0.width, rig.cam0.height, params_).size() < 1 || rig.cam0.width < 16 || rig.cam0.height < 16)
    throw Error("images of " + std::to_string(rig.cam0.width) + "x" + std::to_string(rig.cam0.height) +
                " are too small (at least 16x16)");
  fields_ = computeFields(rig_.cam0, rig_.cam1, rig_.R, rig_.t, {params_.maxFovDeg, params_.epipoleDeg});
  backend_ = createBackend(backend, &backendWhy_);
  backendName_ = backend_->name();
  pipeline_ = std::make_unique<Pipeline>(*backend_, rig_, params_, fields_, ImageU8());
}

Stereo::~Stereo() = default;

void Stereo::setMask(const ImageU8& mask) {
  if (mask.width != rig_.cam0.width || mask.height != rig_.cam0.height)
    throw Error("mask is " + std::to_string(mask.width) + "x" + std::to_string(mask.height) + " but the images are " +
                std::to_string(rig_.cam0.width) + "x" + std::to_string(rig_.cam0.height));
  for (size_t i = 0; i < mask.size(); ++i)
    if (!mask.data[i]) fields_.mask.data[i] = 0;
  pipeline_ = std::make_unique<Pipeline>(*backend_, rig_, params_, fields_, mask);
}

void Stereo::setProgress(std::function<void(double)> progress) { progress_ = std::move(progress); }

const std::string& Stereo::backendName() const { return backendName_; }
std::string Stereo::deviceName() const { return backend_->device(); }

DepthResult Stereo::compute(const ImageF& left, const ImageF& right) {
  checkImage(left, rig_.cam0, "left");
  checkImage(right, rig_.cam1, "right");
  auto t0 = std::chrono::steady_clock::now();
  Pipeline::Output out = pipeline_->run(left, right, progress_);

  DepthResult r;
  r.valid = fields_.mask;
  r.disparity = out.disparity;
  r.warp = out.warp;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (size_t i = 0; i < r.valid.size(); ++i) {
    // A non-finite solution would be a solver failure: report the pixel as unsolved
    // rather than pass a NaN on as if it were depth.
    bool finite = std::isfinite(r.disparity.data[i]) && std::isfinite(r.warp.data[i].x) && std::isfinite(r.warp.data[i].y);
    if (!finite) r.valid.data[i] = 0;
    if (!r.valid.data[i]) {
      r.disparity.data[i] = nan;
      r.warp.data[i] = {nan, nan};
    }
  }
  auto t1 = std::chrono::steady_clock::now();
  r.depth = triangulate(rig_.cam0, rig_.tPrime(), r.warp, r.valid);
  auto t2 = std::chrono::steady_clock::now();
  r.stages = out.stages;
  r.stages.push_back({"triangulate", std::chrono::duration<double, std::milli>(t2 - t1).count()});
  r.totalMs = std::chrono::duration<double, std::milli>(t2 - t0).count();
  return r;
}

}  // namespace cs

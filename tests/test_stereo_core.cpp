// The construction and validation that cs::Stereo and cs::cuda::DeviceStereo share
// (core/src/stereo_core.hpp: detail::StereoCore), on the CPU backend: what is refused,
// in which order (the backend is made only for a good rig and parameters), and what
// setPose / setMask keep.
#include <Eigen/Geometry>
#include <memory>
#include <string>

#include "cpu_backend.hpp"
#include "curvestereo/params.hpp"
#include "curvestereo/stereo.hpp"
#include "forwarding_backend.hpp"
#include "pipeline.hpp"
#include "stereo_core.hpp"
#include "synth/scene.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

Rig smallRig() {
  Rig rig;
  rig.cam0 = rig.cam1 = synth::defaultFisheye(64);
  rig.t = Eigen::Vector3d(-0.1, 0, 0);
  return rig;
}

// The message StereoCore gives for (rig, params), and how often it made a backend.
std::string refusal(const Rig& rig, const Params& params, int& made) {
  made = 0;
  try {
    detail::StereoCore core(rig, params, [&] {
      ++made;
      return std::make_unique<cpu::CpuBackend>();
    });
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// A CPU backend that adds up the bytes of every buffer the pipeline creates.
class CountingBackend final : public test::ForwardingBackend {
 public:
  CountingBackend(std::unique_ptr<Backend> inner, unsigned long long& bytes)
      : ForwardingBackend(*inner), inner_(std::move(inner)), bytes_(bytes) {}

 protected:
  Buffer doCreate(int w, int h, int c) override {
    bytes_ += 4ull * (unsigned long long)w * h * c;
    return ForwardingBackend::doCreate(w, h, c);
  }

 private:
  std::unique_ptr<Backend> inner_;
  unsigned long long& bytes_;
};

}  // namespace

TEST_CASE("bufferBytes: what the pipeline allocates, with and without the sweep") {
  for (const std::string& name : presetNames()) {
    CAPTURE(name);
    unsigned long long created = 0;
    detail::StereoCore core(smallRig(), preset(name), [&] {
      return std::make_unique<CountingBackend>(std::make_unique<cpu::CpuBackend>(), created);
    });
    CHECK(created == Pipeline::bufferBytes(smallRig(), preset(name)));
  }
  Stereo realtime(smallRig(), preset("realtime"), "cpu"), variational(smallRig(), preset("variational"), "cpu");
  CHECK(realtime.bufferBytes() == Pipeline::bufferBytes(smallRig(), preset("realtime")));
  CHECK(realtime.bufferBytes() > variational.bufferBytes());  // the sweep's volumes
}

TEST_CASE("StereoCore refuses a bad rig or parameters before making the backend, as Stereo does") {
  const Params params = preset("realtime");
  int made = 0;
  CHECK(refusal(smallRig(), params, made).empty());
  CHECK(made == 1);

  struct Case {
    Rig rig;
    Params params;
    const char* needle;
  };
  std::vector<Case> cases;
  Rig r = smallRig();
  r.cam0 = r.cam1 = synth::defaultFisheye(64).scaled(12 / 64.0);
  cases.push_back({r, params, "too small (at least 16x16)"});
  r = smallRig(), r.cam0 = r.cam1 = synth::defaultFisheye(64).scaled(40000 / 64.0);
  cases.push_back({r, params, "too large (at most 32768 px per side)"});
  r = smallRig(), r.cam1 = synth::defaultFisheye(64).scaled(40000 / 64.0);  // either camera
  cases.push_back({r, params, "too large (at most 32768 px per side)"});
  r = smallRig(), r.t = Eigen::Vector3d::Zero();
  cases.push_back({r, params, "zero baseline"});
  Params bad = params;
  bad.warps = 0;
  cases.push_back({smallRig(), bad, "warps"});
  for (const Case& c : cases) {
    CAPTURE(c.needle);
    const std::string what = refusal(c.rig, c.params, made);
    CHECK(what.find(c.needle) != std::string::npos);
    CHECK(what.find('\n') == std::string::npos);
    CHECK(made == 0);
    // cs::Stereo is this code: the same message.
    CHECK_THROWS_WITH_AS(Stereo(c.rig, c.params, "cpu"), what.c_str(), Error);
    CHECK_THROWS_WITH_AS(detail::StereoCore::validate(c.rig, c.params), what.c_str(), Error);
  }
}

TEST_CASE("StereoCore: setPose and setMask validate first, and keep the state on an error") {
  detail::StereoCore core(smallRig(), preset("realtime"), [] { return std::make_unique<cpu::CpuBackend>(); });
  CHECK(core.backendName() == "cpu");
  Pipeline* const pipeline = &core.pipeline();

  CHECK_THROWS_WITH_AS(core.setPose(2 * Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.1, 0, 0)),
                       doctest::Contains("not a rotation"), Error);
  CHECK(core.rig().R == Eigen::Matrix3d::Identity());
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitY()).toRotationMatrix();
  core.setPose(R, Eigen::Vector3d(-0.12, 0, 0));
  CHECK(core.rig().R == R);
  CHECK(core.rig().t.x() == -0.12);

  CHECK_THROWS_WITH_AS(core.setMask(ImageU8(32, 64, 1)), "mask is 32x64 but the images are 64x64", Error);
  core.setMask(ImageU8(64, 64, 1));
  CHECK_THROWS_AS(core.setMask(ImageU8()), Error);  // an empty mask is not the images' size either
  CHECK(&core.pipeline() == pipeline);              // the buffers (and a recorded frame) stay
}

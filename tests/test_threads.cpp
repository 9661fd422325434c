// Thread safety (issue 6): Stereo objects share nothing a caller can see, so two of them
// used from two threads at once give bit-identical results to using them one after the
// other. (One Stereo object is not thread-safe; see docs/guide.md "Thread safety".)
#include <cstring>
#include <thread>
#include <vector>

#include "curvestereo/stereo.hpp"
#include "synth/scene.hpp"
#include "test_util.hpp"

using namespace cs;

namespace {

synth::SynthPair render(const std::string& motion, uint32_t seed) {
  return test::smallSynthPair(96, motion, 0.2, seed);
}

template <class T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

bool sameBits(const DepthResult& a, const DepthResult& b) {
  return sameBits(a.valid.data, b.valid.data) && sameBits(a.disparity.data, b.disparity.data) &&
         sameBits(a.warp.data, b.warp.data) && sameBits(a.depth.radial.data, b.depth.radial.data) &&
         sameBits(a.depth.z.data, b.depth.z.data) && sameBits(a.depth.points.data, b.depth.points.data);
}

}  // namespace

TEST_CASE("two Stereo objects in two threads give bit-identical results to sequential use") {
  const synth::SynthPair a = render("binocular", 11), b = render("forward", 12);
  Params params = preset("realtime");
  params.warps = 3;
  constexpr int kFrames = 3;

  // Sequential reference: one object after the other.
  std::vector<DepthResult> refA, refB;
  {
    Stereo sa(a.rig, params, "cpu"), sb(b.rig, params, "cpu");
    for (int f = 0; f < kFrames; ++f) refA.push_back(sa.compute(a.left, a.right));
    for (int f = 0; f < kFrames; ++f) refB.push_back(sb.compute(b.left, b.right));
  }
  // Concurrent: each thread constructs and drives its own object, several frames each so
  // the two solves overlap (and contend for the CPU backend's row pool).
  for (int round = 0; round < 2; ++round) {
    std::vector<DepthResult> gotA, gotB;
    std::thread ta([&] {
      Stereo s(a.rig, params, "cpu");
      for (int f = 0; f < kFrames; ++f) gotA.push_back(s.compute(a.left, a.right));
    });
    std::thread tb([&] {
      Stereo s(b.rig, params, "cpu");
      for (int f = 0; f < kFrames; ++f) gotB.push_back(s.compute(b.left, b.right));
    });
    ta.join();
    tb.join();
    for (int f = 0; f < kFrames; ++f) {
      CAPTURE(round);
      CAPTURE(f);
      CHECK(sameBits(gotA[size_t(f)], refA[size_t(f)]));
      CHECK(sameBits(gotB[size_t(f)], refB[size_t(f)]));
    }
  }
}

TEST_CASE("four threads on the same rig agree bit for bit") {
  const synth::SynthPair a = render("binocular", 13);
  Params params = preset("realtime");
  params.warps = 2;
  Stereo reference(a.rig, params, "cpu");
  const DepthResult ref = reference.compute(a.left, a.right);
  std::vector<DepthResult> got(4);
  std::vector<std::thread> threads;
  for (size_t t = 0; t < got.size(); ++t)
    threads.emplace_back([&, t] {
      Stereo s(a.rig, params, "cpu");
      got[t] = s.compute(a.left, a.right);
    });
  for (auto& t : threads) t.join();
  for (const DepthResult& r : got) CHECK(sameBits(r, ref));
}

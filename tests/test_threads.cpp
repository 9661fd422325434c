// Thread safety (issue 6): Stereo objects share nothing a caller can see, so two of them
// used from two threads at once give bit-identical results to using them one after the
// other. (One Stereo object is not thread-safe; see docs/guide.md "Thread safety".) And the
// host pool that backends share: copyHost and copyFloats split over it give memcpy's bytes.
#include <algorithm>
#include <cstring>
#include <limits>
#include <thread>
#include <vector>

#include "curvestereo/backend.hpp"
#include "curvestereo/host_threads.hpp"
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

// The GPU backends' downloads (copyHost): copies of odd sizes, empty ones among them, whose
// pieces over the pool's threads cross from one copy into the next: every byte lands where
// memcpy would put it, and nothing beyond.
TEST_CASE("copyHost copies every byte of every copy, split over threads or not") {
  for (const std::vector<size_t>& sizes :
       std::vector<std::vector<size_t>>{{1, 0, 17}, {3000001, 0, 777777, 5, 1 << 20}, {600000}}) {
    std::vector<std::vector<unsigned char>> sources, targets;
    std::vector<HostCopy> copies;
    for (size_t k = 0; k < sizes.size(); ++k) {
      sources.emplace_back(sizes[k]);
      for (size_t i = 0; i < sizes[k]; ++i) sources.back()[i] = (unsigned char)((i * 131 + k * 7) % 251);
      targets.emplace_back(sizes[k] + 8, (unsigned char)0xAB);  // 8 guard bytes after each
    }
    for (size_t k = 0; k < sizes.size(); ++k) copies.push_back({targets[k].data(), sources[k].data(), sizes[k]});
    copyHost(copies);
    for (size_t k = 0; k < sizes.size(); ++k) {
      INFO("copy " << k << " of " << sizes[k] << " bytes");
      CHECK(std::equal(sources[k].begin(), sources[k].end(), targets[k].begin()));
      CHECK(std::all_of(targets[k].end() - 8, targets[k].end(), [](unsigned char v) { return v == 0xAB; }));
    }
  }
}

// Backend::upload's copy of a large image goes in pieces over the threads, each with its
// own answer: a NaN or infinity in any piece, at either end of one, is found, and the
// floats (the NaN's bits too) arrive as they were.
TEST_CASE("copyFloats finds a non-finite value in any piece of a large copy") {
  const size_t n = size_t(1) << 20;  // 4 MiB: the most pieces copyPieces makes
  std::vector<float> src(n);
  for (size_t i = 0; i < n; ++i) src[i] = float(i % 9973) * 0.25f - 7.f;
  std::vector<float> dst(n);
  bool finite = false;
  copyFloats(dst.data(), src.data(), n, &finite);
  CHECK(finite);
  CHECK(std::memcmp(dst.data(), src.data(), n * sizeof(float)) == 0);
  const int pieces = copyPieces(n * sizeof(float));
  const size_t lastOfFirstPiece = n / size_t(pieces) - 1;
  for (size_t at : {size_t(0), lastOfFirstPiece, lastOfFirstPiece + 1, n / 2, n - 1}) {
    for (float bad : {std::numeric_limits<float>::quiet_NaN(), -std::numeric_limits<float>::infinity()}) {
      std::vector<float> with = src;
      with[at] = bad;
      finite = true;
      copyFloats(dst.data(), with.data(), n, &finite);
      INFO("value " << bad << " at " << at << " of " << n << " in " << pieces << " pieces");
      CHECK(!finite);
      CHECK(std::memcmp(dst.data(), with.data(), n * sizeof(float)) == 0);
    }
  }
}

// Thread safety (issue 6): Stereo objects share nothing a caller can see, so two of them
// used from two threads at once give bit-identical results to using them one after the
// other. (One Stereo object is not thread-safe; see docs/guide.md "Thread safety".) And the
// host thread pool they share.
#include <atomic>
#include <cstring>
#include <limits>
#include <thread>
#include <vector>

#include "curvestereo/backend.hpp"
#include "curvestereo/parallel.hpp"
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

// The host pool (core/internal/curvestereo/parallel.hpp) that the CPU backend's rows and the
// GPU backends' copies run on.
TEST_CASE("parallelFor visits every item once, in order per worker, nested and from two callers") {
  for (int n : {0, 1, 2, 3, 7, 64, 1000}) {
    std::vector<std::atomic<int>> visits(static_cast<size_t>(n));
    detail::parallelFor(n, [&](int i) { visits[size_t(i)]++; });
    for (int i = 0; i < n; ++i) REQUIRE(visits[size_t(i)].load() == 1);
  }
  // A body that calls parallelFor again runs that loop itself (no self-deadlock).
  std::vector<std::atomic<int>> inner(16 * 16);
  detail::parallelFor(16, [&](int i) { detail::parallelFor(16, [&](int j) { inner[size_t(16 * i + j)]++; }); });
  for (auto& v : inner) REQUIRE(v.load() == 1);
  // Two callers at once: one gets the pool, the other runs its loop itself.
  std::vector<std::atomic<int>> a(500), b(500);
  std::thread other([&] { detail::parallelFor(500, [&](int i) { b[size_t(i)]++; }); });
  detail::parallelFor(500, [&](int i) { a[size_t(i)]++; });
  other.join();
  for (size_t i = 0; i < a.size(); ++i) REQUIRE((a[i].load() == 1 && b[i].load() == 1));
}

TEST_CASE("parallelPieces covers a range with fixed pieces whatever the threads") {
  for (size_t n : {size_t(0), size_t(1), size_t(5), size_t(4096), size_t(10001)}) {
    std::vector<int> covered(n, 0);
    std::vector<std::pair<size_t, size_t>> pieces((n + 999) / 1000);
    detail::parallelPieces(n, 1000, [&](size_t begin, size_t end) {
      pieces[begin / 1000] = {begin, end};
      for (size_t i = begin; i < end; ++i) covered[i]++;
    });
    for (int c : covered) REQUIRE(c == 1);
    for (size_t k = 0; k < pieces.size(); ++k) {
      CHECK(pieces[k].first == 1000 * k);
      CHECK(pieces[k].second == std::min(n, 1000 * (k + 1)));
    }
  }
}

TEST_CASE("copyFloats copies exactly and reports a non-finite pixel in any piece") {
  std::vector<float> src(300000), dst(src.size());
  for (size_t i = 0; i < src.size(); ++i) src[i] = float(i) * 0.5f - 7.f;
  bool finite = false;
  copyFloats(dst.data(), src.data(), src.size(), &finite);
  CHECK(finite);
  CHECK(std::memcmp(dst.data(), src.data(), src.size() * sizeof(float)) == 0);
  for (size_t at : {size_t(0), size_t(65535), size_t(65536), size_t(299999)}) {
    std::vector<float> bad = src;
    bad[at] = std::numeric_limits<float>::infinity();
    copyFloats(dst.data(), bad.data(), bad.size(), &finite);
    CHECK_FALSE(finite);
  }
  std::vector<uint8_t> bytes(1 << 20), out(bytes.size());
  for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = uint8_t(i * 7 + (i >> 9));
  copyBytes(out.data(), bytes.data(), bytes.size());
  CHECK(out == bytes);
}

// Reading frames cheaply (issue 31, reading cost): the chunk cache decompresses each chunk
// once and lets distinct chunks decompress in parallel; SequenceReader reads frames ahead on
// background threads, hands them out in order, and raises an unreadable frame's error at
// its turn, after every frame before it.
#include <atomic>
#include <chrono>
#include <filesystem>
#include <thread>

#include "cli_util.hpp"
#include "curvestereo/image_io.hpp"
#include "curvestereo/log.hpp"
#include "log_reader.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using cs::logio::ChunkCache;
using cs::logio::ChunkData;
using cs::test::CliOutcome;
using cs::test::runCli;

namespace {

ChunkData chunkOf(uint64_t bytes, uint8_t fill) {
  std::shared_ptr<uint8_t[]> buffer(new uint8_t[bytes]);
  std::fill(buffer.get(), buffer.get() + bytes, fill);
  return ChunkData{buffer, buffer.get(), bytes};
}

// Frames i = 0.. of a "LEFT,RIGHT" PNG folder sequence, each image filled with i / 255.
std::string writeFrames(const fs::path& dir, int frames) {
  fs::create_directories(dir / "l");
  fs::create_directories(dir / "r");
  for (int i = 0; i < frames; ++i) {
    cs::ImageF image(8, 6);
    std::fill(image.data.begin(), image.data.end(), float(i) / 255.f);
    const std::string name = std::to_string(1'000'000'000 + i * 33'333'333) + ".png";
    cs::writePngGray((dir / "l" / name).string(), image);
    cs::writePngGray((dir / "r" / name).string(), image);
  }
  return (dir / "l").string() + "," + (dir / "r").string();
}

}  // namespace

TEST_CASE("chunk cache: chunks kept at scan are not decompressed again, within the budget") {
  ChunkCache cache(1000);
  cache.keep(10, chunkOf(600, 1));
  cache.keep(20, chunkOf(600, 2));  // over the budget: not kept (the first chunks are)
  int loads = 0;
  const auto load = [&](uint8_t fill) {
    return [&, fill] {
      ++loads;
      return chunkOf(300, fill);
    };
  };
  CHECK(cache.get(10, load(9)).data[0] == 1);
  CHECK(loads == 0);
  CHECK(cache.get(20, load(2)).data[0] == 2);
  CHECK(loads == 1);
  CHECK(cache.get(20, load(7)).data[0] == 2);  // found, not loaded again
  CHECK(loads == 1);
  CHECK(cache.loads() == 1);
}

TEST_CASE("chunk cache: the least recently used chunk goes first; a chunk in use stays valid") {
  ChunkCache cache(1000);
  const auto load = [](uint8_t fill) { return [fill] { return chunkOf(400, fill); }; };
  const ChunkData first = cache.get(1, load(1));
  cache.get(2, load(2));
  cache.get(1, load(1));  // 1 used after 2
  cache.get(3, load(3));  // 1200 bytes: 2 goes
  CHECK(cache.loads() == 3);
  cache.get(1, load(1));
  CHECK(cache.loads() == 3);
  cache.get(2, load(2));
  CHECK(cache.loads() == 4);
  CHECK(first.data[399] == 1);  // its owner keeps it alive through eviction
}

TEST_CASE("chunk cache: an error reaches the caller and is not kept; one load for concurrent readers") {
  ChunkCache cache;
  CHECK_THROWS_WITH_AS(cache.get(5, []() -> ChunkData { throw cs::Error("corrupt chunk"); }), "corrupt chunk",
                       cs::Error);
  CHECK(cache.get(5, [] { return chunkOf(10, 4); }).data[0] == 4);  // tried again
  std::atomic<int> loads{0};
  std::vector<std::thread> threads;
  std::atomic<int> sum{0};
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&] {
      const ChunkData c = cache.get(6, [&] {
        ++loads;
        std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the others arrive meanwhile
        return chunkOf(10, 6);
      });
      sum += c.data[0];
    });
  for (std::thread& t : threads) t.join();
  CHECK(loads == 1);
  CHECK(sum == 24);
}

TEST_CASE("decompressAhead: chunks used in file order; the first corrupt one in file order is raised") {
  const std::vector<uint64_t> chunks = {10, 20, 30, 40, 50, 60};
  const auto decompress = [](uint64_t offset) {
    // Later chunks finish first: the order of use must not follow the order of completion.
    std::this_thread::sleep_for(std::chrono::milliseconds(int(70 - offset)));
    if (offset == 40 || offset == 50) throw cs::Error("corrupt chunk " + std::to_string(offset));
    return chunkOf(4, uint8_t(offset));
  };
  for (unsigned threads : {1u, 3u, 8u}) {
    CAPTURE(threads);
    std::vector<uint64_t> used;
    const auto use = [&](uint64_t offset, const ChunkData& c) {
      CHECK(c.data[0] == uint8_t(offset));
      used.push_back(offset);
    };
    CHECK_THROWS_WITH_AS(cs::logio::decompressAhead(chunks, decompress, use, threads), "corrupt chunk 40", cs::Error);
    CHECK(used == std::vector<uint64_t>{10, 20, 30});
    used.clear();
    cs::logio::decompressAhead({10, 20, 30}, decompress, use, threads);
    CHECK(used == std::vector<uint64_t>{10, 20, 30});
  }
}

// Scans a log for two topics' messages and reads each one back: the chunks read() had to
// decompress again.
uint64_t chunksDecompressedAgain(const std::string& path, bool keep = true) {
  const auto reader = cs::logio::openReader(path);
  reader->keepChunks(keep);
  std::vector<cs::logio::MessageRef> refs;
  reader->scan({}, [&](const cs::logio::MessageRef& ref, const uint8_t*, size_t) { refs.push_back(ref); });
  REQUIRE(refs.size() >= 12);
  REQUIRE(refs.front().chunk != refs.back().chunk);  // several chunks
  for (const auto& ref : refs) reader->read(ref, [](const uint8_t*, size_t n) { CHECK(n > 0); });
  return reader->chunkLoads();
}

TEST_CASE("a log's chunks are decompressed once: at opening, then found by every frame's read") {
  const fs::path dir = cs::test::tempDir("log_reading_once");
  const cs::Sequence images = cs::Sequence::open(writeFrames(dir, 6));
  for (const char* compression : {"zstd", "lz4"}) {
    CAPTURE(compression);
    cs::ImageLogOptions o;
    o.compression = compression;
    o.chunkBytes = 200;  // a chunk a frame or so
    const std::string path = (dir / (std::string(compression) + ".mcap")).string();
    cs::writeImageLog(path, images, o);
    CHECK(chunksDecompressedAgain(path) == 0);
    CHECK(chunksDecompressedAgain(path, false) >= 2);  // a listing keeps none: each read decompresses
    const cs::Sequence log = cs::Sequence::openLog(path, "/cam0/image_raw", "/cam1/image_raw");
    cs::ImageF l, r;
    for (size_t i = 0; i < log.frames().size(); ++i) {
      log.load(i, l, r);
      CHECK(l.data[0] == doctest::Approx(float(i) / 255.f));
    }
  }
  const std::string logs = cs::test::sharedData("logs");
  if (logs.empty()) {
    MESSAGE("skipped the shared bz2 bag: ../shared/data/logs is not present");
    return;
  }
  CHECK(chunksDecompressedAgain(logs + "/seqD1_ros1.bag") == 0);
  CHECK(chunksDecompressedAgain(logs + "/seqD1_image_zstd.mcap") == 0);
  fs::remove_all(dir);
}

TEST_CASE("SequenceReader: frames in order, equal to load(), with any number of threads") {
  const fs::path dir = cs::test::tempDir("log_reading_ahead");
  const cs::Sequence seq = cs::Sequence::open(writeFrames(dir, 7));
  for (int threads : {1, 3, 16}) {
    CAPTURE(threads);
    cs::SequenceReader reader(seq, threads);
    CHECK(reader.threads() == std::min(threads, 7));
    cs::ImageF l, r;
    size_t index = 99, expected = 0;
    while (reader.next(index, l, r)) {
      CHECK(index == expected);
      CHECK(l.data[0] == doctest::Approx(float(expected) / 255.f));
      CHECK(r.data[5] == doctest::Approx(float(expected) / 255.f));
      ++expected;
    }
    CHECK(expected == 7);
    CHECK_FALSE(reader.next(index, l, r));
    CHECK(reader.readMs() > 0);
  }
  { cs::SequenceReader early(seq, 2); }   // destroyed before reading everything: stops cleanly
  cs::SequenceReader part(seq, 2, 2, 5);  // frames 2, 3, 4 alone
  cs::ImageF l, r;
  std::vector<size_t> got;
  for (size_t index = 0; part.next(index, l, r);) got.push_back(index);
  CHECK(got == std::vector<size_t>{2, 3, 4});
  cs::SequenceReader tail(seq, 1, 6, 100);  // an end past the last frame: to the last
  size_t index = 0;
  CHECK(tail.next(index, l, r));
  CHECK(index == 6);
  CHECK_FALSE(tail.next(index, l, r));
  fs::remove_all(dir);
}

TEST_CASE("SequenceReader: an unreadable frame raises its load() error at its turn, after the frames before") {
  const fs::path dir = cs::test::tempDir("log_reading_bad");
  const cs::Sequence seq = cs::Sequence::open(writeFrames(dir, 6));
  fs::remove(seq.frames()[3].rightPath);
  cs::SequenceReader reader(seq, 4);
  cs::ImageF l, r;
  size_t index = 0;
  for (size_t i = 0; i < 3; ++i) {
    REQUIRE(reader.next(index, l, r));
    CHECK(index == i);
  }
  CHECK_THROWS_WITH_AS(reader.next(index, l, r), doctest::Contains("frame 3 (t 1099999999 ns), right image"),
                       cs::Error);
  CHECK_FALSE(reader.next(index, l, r));  // nothing after it
  fs::remove_all(dir);
}

TEST_CASE("log info --time-read: what opening and reading a log cost, one line; misuse is refused") {
  const fs::path dir = cs::test::tempDir("log_reading_cli");
  cs::writeImageLog((dir / "seq.mcap").string(), cs::Sequence::open(writeFrames(dir, 3)));
  CliOutcome r = runCli(dir, "log info seq.mcap --time-read --topics /cam0/image_raw,/cam1/image_raw --read-threads 1");
  INFO(r.err);
  CHECK(r.exitCode == 0);
  CHECK(r.out.find("seq.mcap: 3 stereo frames (MCAP, zstd chunks") != std::string::npos);
  CHECK(r.out.find("3 frames (8x6) read in") != std::string::npos);
  CHECK(r.out.find("ms a frame") != std::string::npos);
  CHECK(r.out.find("read ahead on 1 thread against a 2.50 ms solve: the solving thread waited") != std::string::npos);
  r = runCli(dir,
             "log info seq.mcap --time-read --topics /cam0/image_raw,/cam1/image_raw --solve-ms 0 --read-threads 2");
  CHECK(r.exitCode == 0);
  CHECK(r.out.find("read ahead on 2 threads against a 0.00 ms solve") != std::string::npos);
  r = runCli(dir, "log info seq.mcap --time-read");
  CHECK(r.exitCode == 2);
  CHECK(r.err.find("--topics") != std::string::npos);
  r = runCli(dir, "log info seq.mcap --time-read --topics /cam0/image_raw,/nope");
  CHECK(r.exitCode == 1);
  CHECK(r.err.find("has no topic '/nope'") != std::string::npos);
  r = runCli(dir, "log write --time-read --sequence x -o y.mcap");
  CHECK(r.exitCode == 2);
  CHECK(r.err.find("--time-read is for log info --time-read") != std::string::npos);
  r = runCli(dir, "log info seq.mcap --solve-ms 3");
  CHECK(r.exitCode == 2);
  CHECK(r.err.find("--solve-ms is for log info --time-read") != std::string::npos);
}

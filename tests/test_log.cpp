// Recorded logs in (issue 31): the three logs of ../shared/data/logs give the image files'
// frames bit for bit (and so the same depth), logs written here read back (every chunk
// compression), rosbag2 sqlite3 from a fixture generated here, and bad input: a cut log read
// up to the cut, a bad CRC, a missing topic, an unsupported encoding, each one clear line.
#include <sqlite3.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "curvestereo/image_io.hpp"
#include "curvestereo/log.hpp"
#include "curvestereo/stereo.hpp"
#include "log_reader.hpp"
#include "mcap_writer.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

const char* const kLeft = "/cam0/image_raw";
const char* const kRight = "/cam1/image_raw";

// A small "LEFT,RIGHT" sequence of PNGs named by timestamp (30 fps), 8-bit or 16-bit.
std::string writeSequence(const fs::path& dir, int frames, int w, int h, bool sixteen = false) {
  fs::create_directories(dir / "l");
  fs::create_directories(dir / "r");
  for (int i = 0; i < frames; ++i) {
    cs::ImageF l(w, h), r(w, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        l.data[size_t(y * w + x)] = float(((x * 7 + y * 13 + i * 5) % 256) / 255.0);
        r.data[size_t(y * w + x)] = float(((x * 11 + y * 3 + i * 17) % 256) / 255.0);
      }
    const std::string name = std::to_string(1'000'000'000'000 + int64_t(i) * 33'333'333) + ".png";
    (sixteen ? cs::writePngGray16 : cs::writePngGray)((dir / "l" / name).string(), l);
    (sixteen ? cs::writePngGray16 : cs::writePngGray)((dir / "r" / name).string(), r);
  }
  return (dir / "l").string() + "," + (dir / "r").string();
}

void requireSameImages(const cs::Sequence& a, const cs::Sequence& b, size_t frames) {
  REQUIRE(a.frames().size() >= frames);
  REQUIRE(b.frames().size() >= frames);
  cs::ImageF al, ar, bl, br;
  for (size_t i = 0; i < frames; ++i) {
    CAPTURE(i);
    CHECK(a.frames()[i].timestampNs == b.frames()[i].timestampNs);
    a.load(i, al, ar);
    b.load(i, bl, br);
    REQUIRE(al.width == bl.width);
    CHECK(al.data == bl.data);  // bit for bit
    CHECK(ar.data == br.data);
  }
}

// Through the stream buffer in one go: a character at a time (istreambuf_iterator) was a
// third of the cut-log case under the sanitizers.
std::string readAll(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}
void writeAll(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

using cs::test::errorOf;

}  // namespace

TEST_CASE("the shared logs give the sequence's frames bit for bit, and the same depth") {
  const std::string seq = cs::test::sharedData("sequences/seqD1_indoor_walk");
  const std::string logs = cs::test::sharedData("logs");
  if (seq.empty() || logs.empty()) {
    MESSAGE("skipped: ../shared/data/logs or sequences/seqD1_indoor_walk is not present");
    return;
  }
  const cs::Sequence images = cs::Sequence::open(seq);
  const std::vector<std::array<std::string, 3>> cases = {
      {"seqD1_image_zstd.mcap", "/cam0/image_raw", "/cam1/image_raw"},
      {"seqD1_compressed_png.mcap", "/camera/left/image_raw/compressed", "/camera/right/image_raw/compressed"},
      {"seqD1_ros1.bag", "/camera/fisheye1/image_raw", "/camera/fisheye2/image_raw"}};
  for (const auto& [file, left, right] : cases) {
    CAPTURE(file);
    const cs::Sequence log = cs::Sequence::openLog(logs + "/" + file, left, right);
    CHECK(log.frames().size() == images.frames().size());
    CHECK(log.warnings().empty());
    // Under the sanitizers the first 4 frames: every frame takes the same reader code.
    requireSameImages(log, images, CS_SANITIZED ? 4 : images.frames().size());
  }
  // The same depth from either source through Stereo::next (a short solve on the CPU
  // oracle: the images are already bit-identical, this checks they reach the solver so; two
  // full solves a frame took a minute under the sanitizers). Under the sanitizers the first
  // frame only, and without the plane sweep (preset variational): the images reach the
  // solver the same way whatever it then does with them (the second frame's warm start and
  // the sweep are the solver's own, checked by other suites), and the two frames' four
  // 848x800 solves were nine tenths of this suite's time there.
  const cs::Rig rig = cs::loadCalibration(seq + "/camchain.yaml");
  const cs::Sequence log = cs::Sequence::openLog(logs + "/seqD1_image_zstd.mcap", kLeft, kRight);
  cs::Params quick = cs::preset(CS_SANITIZED ? "variational" : "fast");
  quick.warps = 1;
  cs::Stereo a(rig, quick, "cpu"), b(rig, quick, "cpu");
  cs::ImageF l, r;
  cs::DepthResult ra, rb;
  for (size_t i = 0; i < (CS_SANITIZED ? 1 : 2); ++i) {
    images.load(i, l, r);
    a.next(l, r, ra);
    log.load(i, l, r);
    b.next(l, r, rb);
    CHECK(std::memcmp(ra.depth.radial.data.data(), rb.depth.radial.data.data(), ra.depth.radial.size() * 4) == 0);
  }
}

TEST_CASE("log info lists the shared logs' topics, types, counts and formats") {
  const std::string logs = cs::test::sharedData("logs");
  if (logs.empty()) {
    MESSAGE("skipped: ../shared/data/logs is not present");
    return;
  }
  const cs::LogInfo mcap = cs::logInfo(logs + "/seqD1_image_zstd.mcap");
  CHECK(mcap.format.find("zstd") != std::string::npos);
  CHECK(mcap.format.find("index") != std::string::npos);
  REQUIRE(mcap.topics.size() == 2);
  CHECK(mcap.topics[0].type == "sensor_msgs/msg/Image");
  CHECK(mcap.topics[0].messages == 16);
  CHECK(mcap.messages == 32);
  const cs::LogInfo bag = cs::logInfo(logs + "/seqD1_ros1.bag");
  CHECK(bag.format.find("bz2") != std::string::npos);
  CHECK(bag.topics.size() == 2);
  CHECK(bag.topics[0].serialisation == "ros1");
  CHECK(bag.endNs - bag.startNs == 500'000'000);  // 16 frames at 30 fps, log times
}

TEST_CASE("a shared log cut short is read up to the cut, with one line saying where") {
  const std::string logs = cs::test::sharedData("logs");
  if (logs.empty()) {
    MESSAGE("skipped: ../shared/data/logs is not present");
    return;
  }
  const fs::path dir = cs::test::tempDir("log_cut_shared");
  for (const char* file : {"seqD1_image_zstd.mcap", "seqD1_ros1.bag", "seqD1_compressed_png.mcap"}) {
    CAPTURE(file);
    const std::string whole = readAll(fs::path(logs) / file);
    writeAll(dir / file, whole.substr(0, whole.size() * 6 / 10));
    const cs::LogInfo info = cs::logInfo((dir / file).string());
    const std::string& l = info.topics.at(0).name;
    const std::string& r = info.topics.at(1).name;
    const cs::Sequence cut = cs::Sequence::openLog((dir / file).string(), l, r);
    CHECK(cut.frames().size() >= 4);
    CHECK(cut.frames().size() < 16);
    REQUIRE(!cut.warnings().empty());
    CHECK(cut.warnings()[0].find("cut short at byte") != std::string::npos);
    const cs::Sequence full = cs::Sequence::openLog(logs + "/" + file, l, r);
    requireSameImages(cut, full, cut.frames().size());
  }
}

TEST_CASE("image logs written here read back bit for bit, every chunk compression and format") {
  const fs::path dir = cs::test::tempDir("log_roundtrip");
  const std::string source = writeSequence(dir / "seq", 5, 24, 16);
  const cs::Sequence images = cs::Sequence::open(source);
  for (const char* compression : {"none", "zstd", "lz4"})
    for (const char* format : {"raw", "png"}) {
      CAPTURE(compression);
      CAPTURE(format);
      cs::ImageLogOptions o;
      o.compression = compression;
      o.format = format;
      o.chunkBytes = 1500;  // several chunks
      const std::string path = (dir / (std::string(compression) + format + ".mcap")).string();
      cs::writeImageLog(path, images, o);
      const cs::Sequence log = cs::Sequence::openLog(path, kLeft, kRight);
      CHECK(log.frames().size() == 5);
      CHECK(log.warnings().empty());
      requireSameImages(log, images, 5);
      CHECK(cs::logInfo(path).format.find("summary and chunk indexes") != std::string::npos);
    }
  // 16-bit PNGs travel as mono16.
  const cs::Sequence wide = cs::Sequence::open(writeSequence(dir / "seq16", 2, 10, 6, true));
  cs::writeImageLog((dir / "wide.mcap").string(), wide);
  requireSameImages(cs::Sequence::openLog((dir / "wide.mcap").string(), kLeft, kRight), wide, 2);
}

TEST_CASE("a log written here, cut anywhere, gives the frames before the cut or one clean line") {
  const fs::path dir = cs::test::tempDir("log_cut_any");
  const cs::Sequence images = cs::Sequence::open(writeSequence(dir / "seq", 6, 16, 12));
  cs::ImageLogOptions o;
  o.chunkBytes = 1000;
  cs::writeImageLog((dir / "whole.mcap").string(), images, o);
  const std::string whole = readAll(dir / "whole.mcap");
  size_t lastFrames = 0;
  for (size_t cut = 0; cut <= whole.size(); cut += 97) {
    CAPTURE(cut);
    writeAll(dir / "cut.mcap", whole.substr(0, cut));
    const std::string error = errorOf([&] {
      const cs::Sequence s = cs::Sequence::openLog((dir / "cut.mcap").string(), kLeft, kRight);
      requireSameImages(s, images, s.frames().size());
      CHECK(s.frames().size() >= lastFrames);  // more of the file, no fewer frames
      lastFrames = s.frames().size();
    });
    if (!error.empty()) {
      CHECK(error.find('\n') == std::string::npos);
      CHECK(lastFrames == 0);  // only before the first frame is complete
    }
  }
  CHECK(lastFrames == 6);
}

TEST_CASE("bad input: a bad CRC, a missing topic, an unsupported encoding each name the log, topic or message") {
  const fs::path dir = cs::test::tempDir("log_bad");
  const cs::Sequence images = cs::Sequence::open(writeSequence(dir / "seq", 3, 16, 12));
  cs::ImageLogOptions o;
  o.compression = "none";
  cs::writeImageLog((dir / "good.mcap").string(), images, o);
  std::string bytes = readAll(dir / "good.mcap");
  // A pixel changed inside the (uncompressed) chunk: the chunk's CRC no longer matches.
  const size_t pixel = bytes.find(std::string("mono8", 5)) + 40;
  bytes[pixel] = char(bytes[pixel] ^ 0x55);
  writeAll(dir / "crc.mcap", bytes);
  const std::string crc = errorOf([&] { cs::Sequence::openLog((dir / "crc.mcap").string(), kLeft, kRight); });
  CHECK(crc.find("bad CRC in the chunk at byte") != std::string::npos);
  CHECK(crc.find(kLeft) != std::string::npos);  // the chunk's topics
  const std::string missing = errorOf([&] { cs::Sequence::openLog((dir / "good.mcap").string(), "/left", kRight); });
  CHECK(missing == "log '" + (dir / "good.mcap").string() + "' has no topic '/left' (its image topics: " + kLeft +
                       ", " + kRight + ")");
  // An encoding this does not read: yuv422 in the second message of the right topic.
  {
    cs::McapWriter w((dir / "yuv.mcap").string(), "zstd", 1 << 20);
    const uint16_t schema = w.addSchema("sensor_msgs/msg/Image", "ros2msg", "");
    const uint16_t l = w.addChannel(schema, kLeft, "cdr"), r = w.addChannel(schema, kRight, "cdr");
    for (int i = 0; i < 2; ++i)
      for (uint16_t c : {l, r}) {
        cs::CdrBuffer b;
        b.header(1000 + i, "cam");
        b.u32(1), b.u32(2), b.str(c == r && i == 1 ? "yuv422" : "mono8"), b.u8(0), b.u32(2);
        const uint8_t px[2] = {1, 2};
        b.bytes(px, 2);
        w.write(c, uint64_t(1000 + i), b.data());
      }
    w.close();
  }
  const std::string yuv = errorOf([&] { cs::Sequence::openLog((dir / "yuv.mcap").string(), kLeft, kRight); });
  CHECK(yuv == "log '" + (dir / "yuv.mcap").string() + "', topic '/cam1/image_raw', message 1 (logged at 1001 ns): " +
                   "unsupported encoding 'yuv422' (mono8, mono16, rgb8 and bgr8 are read)");
  const std::string notLog = errorOf([&] { cs::Sequence::openLog((dir / "seq" / "l").string(), kLeft, kRight); });
  CHECK(notLog.find("metadata.yaml") != std::string::npos);
}

namespace {

// A rosbag2 sqlite3 bag (metadata.yaml + .db3) as ROS 2's recorder lays it out, holding a
// sequence's frames as CDR sensor_msgs/Image mono8: the fixture for the sqlite3 reader.
void writeRosbag2(const fs::path& dir, const cs::Sequence& seq) {
  fs::create_directories(dir);
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open((dir / "bag_0.db3").string().c_str(), &db) == SQLITE_OK);
  const char* schema =
      "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, serialization_format "
      "TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
      "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data "
      "BLOB NOT NULL);"
      "INSERT INTO topics VALUES (1, '/cam0/image_raw', 'sensor_msgs/msg/Image', 'cdr', ''),"
      "(2, '/cam1/image_raw', 'sensor_msgs/msg/Image', 'cdr', '');";
  REQUIRE(sqlite3_exec(db, schema, nullptr, nullptr, nullptr) == SQLITE_OK);
  sqlite3_stmt* insert = nullptr;
  REQUIRE(sqlite3_prepare_v2(db, "INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)", -1, &insert,
                             nullptr) == SQLITE_OK);
  cs::ImageF l, r;
  for (size_t i = 0; i < seq.frames().size(); ++i) {
    seq.load(i, l, r);
    for (int topic : {1, 2}) {
      const cs::ImageF& img = topic == 1 ? l : r;
      cs::CdrBuffer b;
      b.header(seq.frames()[i].timestampNs, "cam");
      b.u32(uint32_t(img.height)), b.u32(uint32_t(img.width)), b.str("mono8"), b.u8(0), b.u32(uint32_t(img.width));
      std::vector<uint8_t> px(img.size());
      for (size_t k = 0; k < px.size(); ++k) px[k] = uint8_t(std::lround(img.data[k] * 255.0));
      b.bytes(px.data(), px.size());
      sqlite3_bind_int(insert, 1, topic);
      sqlite3_bind_int64(insert, 2, seq.frames()[i].timestampNs + 2'000'000);  // logged 2 ms later
      sqlite3_bind_blob(insert, 3, b.data().data(), int(b.data().size()), SQLITE_TRANSIENT);
      REQUIRE(sqlite3_step(insert) == SQLITE_DONE);
      sqlite3_reset(insert);
    }
  }
  sqlite3_finalize(insert);
  sqlite3_close(db);
  std::ofstream(dir / "metadata.yaml") << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
                                       << "  relative_file_paths:\n    - bag_0.db3\n  message_count: "
                                       << 2 * seq.frames().size() << "\n";
}

}  // namespace

TEST_CASE("rosbag2 sqlite3: a bag folder and its .db3 give the frames bit for bit") {
  const fs::path dir = cs::test::tempDir("log_rosbag2");
  const cs::Sequence images = cs::Sequence::open(writeSequence(dir / "seq", 4, 20, 14));
  writeRosbag2(dir / "bag", images);
  for (const fs::path& p : {dir / "bag", dir / "bag" / "bag_0.db3"}) {
    CAPTURE(p.string());
    const cs::Sequence log = cs::Sequence::openLog(p.string(), kLeft, kRight);
    CHECK(log.summary().find("rosbag2 sqlite3") != std::string::npos);
    requireSameImages(log, images, 4);
  }
  const cs::LogInfo info = cs::logInfo((dir / "bag").string());
  CHECK(info.messages == 8);
  CHECK(info.topics.at(1).serialisation == "cdr");
  writeAll(dir / "bag" / "bag_0.db3", "SQLite format 3\0 but not really" + std::string(200, 'x'));
  const std::string error = errorOf([&] { cs::Sequence::openLog((dir / "bag").string(), kLeft, kRight); });
  CHECK(error.find("rosbag2 database") != std::string::npos);
  CHECK(error.find('\n') == std::string::npos);
}

TEST_CASE("pairing by header.stamp: unpaired messages are reported, never dropped silently") {
  const fs::path dir = cs::test::tempDir("log_pairing");
  cs::McapWriter w((dir / "p.mcap").string(), "none", 1 << 20);
  const uint16_t schema = w.addSchema("sensor_msgs/msg/Image", "ros2msg", "");
  const uint16_t l = w.addChannel(schema, kLeft, "cdr"), r = w.addChannel(schema, kRight, "cdr");
  const auto image = [&](uint16_t c, int64_t stamp) {
    cs::CdrBuffer b;
    b.header(stamp, "cam");
    b.u32(1), b.u32(1), b.str("mono8"), b.u8(0), b.u32(1);
    const uint8_t px = 9;
    b.bytes(&px, 1);
    w.write(c, uint64_t(stamp + 5'000'000), b.data());  // log time later than the stamp
  };
  image(l, 1'000'000'000), image(r, 1'000'400'000);  // 0.4 ms apart: paired
  image(l, 1'033'000'000);                           // no right frame
  image(l, 1'066'000'000), image(r, 1'066'000'000);
  image(r, 1'090'000'000);  // no left frame
  w.close();
  const cs::Sequence s = cs::Sequence::openLog((dir / "p.mcap").string(), kLeft, kRight);
  REQUIRE(s.frames().size() == 2);
  CHECK(s.frames()[0].timestampNs == 1'000'000'000);  // header.stamp, not the log time
  CHECK(s.frames()[1].leftPath == (dir / "p.mcap").string() + ":/cam0/image_raw#2");
  REQUIRE(s.warnings().size() == 2);
  CHECK(s.warnings()[0] == "/cam0/image_raw message 1 (stamp 1033000000 ns): no /cam1/image_raw message within 1 ms");
  CHECK(s.summary().find("2 unpaired") != std::string::npos);
  cs::SequenceOptions tight;
  tight.pairToleranceMs = 0.1;
  CHECK(cs::Sequence::openLog((dir / "p.mcap").string(), kLeft, kRight, tight).frames().size() == 1);
}

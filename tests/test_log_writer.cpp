// Depth logs out (issue 31 item 2): DepthLogWriter's MCAP read back by this project's reader
// (every topic, its CDR fields and pixels bit for bit), and by Foxglove's @mcap/core when node
// and npm are present (npm install into a cache folder; skipped with a message otherwise).
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>

#include "curvestereo/log.hpp"
#include "log_reader.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;

namespace {

cs::Rig smallRig(int w, int h) {
  cs::Rig rig;
  rig.cam0 = cs::Camera::kannalaBrandt4(w, h, 10, 10, (w - 1) / 2.0, (h - 1) / 2.0, 0.01, -0.002, 0.0003, -0.00004);
  rig.cam1 = rig.cam0;
  rig.t = Eigen::Vector3d(-0.1, 0, 0);
  return rig;
}

cs::DepthResult fakeResult(int w, int h, int frame) {
  cs::DepthResult r;
  r.depth.radial = cs::ImageF(w, h);
  r.depth.points = cs::Image<cs::Point3f>(w, h);
  r.confidence = cs::ImageF(w, h);
  for (int i = 0; i < w * h; ++i) {
    const float d = i % 7 == 0 ? NAN : i % 11 == 0 ? INFINITY : 1.0f + 0.01f * float(i + frame);
    r.depth.radial.data[size_t(i)] = d;
    r.depth.points.data[size_t(i)] = {0.1f * float(i), -0.2f * float(frame), d};
    r.confidence.data[size_t(i)] = float(i % 10) / 10.f;
  }
  return r;
}

// The fields of a CDR message, read back in order.
struct Cdr {
  const uint8_t* p;
  size_t n, pos = 4;
  template <typename T>
  T get() {
    pos += (sizeof(T) - (pos - 4) % sizeof(T)) % sizeof(T);
    REQUIRE(pos + sizeof(T) <= n);
    T v;
    std::memcpy(&v, p + pos, sizeof v);
    pos += sizeof v;
    return v;
  }
  std::string str() {
    const uint32_t len = get<uint32_t>();
    REQUIRE(pos + len <= n);
    std::string s(reinterpret_cast<const char*>(p + pos), len ? len - 1 : 0);
    pos += len;
    return s;
  }
  std::vector<uint8_t> bytes() {
    const uint32_t len = get<uint32_t>();
    REQUIRE(pos + len <= n);
    std::vector<uint8_t> v(p + pos, p + pos + len);
    pos += len;
    return v;
  }
};

struct Read {
  std::map<std::string, std::vector<std::vector<uint8_t>>> messages;  // topic -> message bytes
  std::map<std::string, std::string> types;
  std::string format;
};

Read readBack(const std::string& path) {
  Read out;
  auto reader = cs::logio::openReader(path);
  reader->scan({}, [&](const cs::logio::MessageRef& ref, const uint8_t* p, size_t n) {
    out.messages[reader->channels()[ref.channel].topic].emplace_back(p, p + n);
  });
  for (const auto& c : reader->channels()) out.types[c.topic] = c.type;
  out.format = reader->format();
  CHECK(reader->cut().empty());
  return out;
}

}  // namespace

TEST_CASE("DepthLogWriter: depth, camera info, points and confidence read back bit for bit") {
  const fs::path dir = cs::test::tempDir("depth_log");
  const int w = 9, h = 5;
  const cs::Rig rig = smallRig(w, h);
  for (const char* compression : {"zstd", "none", "lz4"}) {
    CAPTURE(compression);
    const std::string path = (dir / (std::string(compression) + ".mcap")).string();
    {
      cs::DepthLogOptions o;
      o.compression = compression;
      o.chunkBytes = 600;
      o.minConfidence = 0.5f;
      o.pinhole = true;
      o.pinholeView = cs::PinholeView::fromFov(90, 6, 4);
      cs::DepthLogWriter writer(path, rig, o);
      for (int f = 0; f < 3; ++f) writer.write(1'700'000'000'123'456'789 + f * 33'333'333, fakeResult(w, h, f));
      writer.close();
    }
    Read back = readBack(path);
    CHECK(back.format.find("summary and chunk indexes") != std::string::npos);
    CHECK(back.types["/curvestereo/depth"] == "sensor_msgs/msg/Image");
    CHECK(back.types["/curvestereo/camera_info"] == "sensor_msgs/msg/CameraInfo");
    CHECK(back.types["/curvestereo/points"] == "sensor_msgs/msg/PointCloud2");
    for (const char* topic :
         {"/curvestereo/depth", "/curvestereo/camera_info", "/curvestereo/points", "/curvestereo/confidence",
          "/curvestereo/depth_pinhole", "/curvestereo/depth_pinhole/camera_info"})
      CHECK(back.messages[topic].size() == 3);
    for (int f = 0; f < 3; ++f) {
      const cs::DepthResult expect = fakeResult(w, h, f);
      const auto& depth = back.messages["/curvestereo/depth"][size_t(f)];
      Cdr d{depth.data(), depth.size()};
      const int64_t stamp = 1'700'000'000'123'456'789 + f * 33'333'333;
      CHECK(d.get<int32_t>() == int32_t(stamp / 1'000'000'000));
      CHECK(d.get<uint32_t>() == uint32_t(stamp % 1'000'000'000));
      CHECK(d.str() == "cam0");
      CHECK(d.get<uint32_t>() == uint32_t(h));
      CHECK(d.get<uint32_t>() == uint32_t(w));
      CHECK(d.str() == "32FC1");
      CHECK(d.get<uint8_t>() == 0);
      CHECK(d.get<uint32_t>() == uint32_t(4 * w));
      const std::vector<uint8_t> pixels = d.bytes();
      REQUIRE(pixels.size() == size_t(4 * w * h));
      CHECK(std::memcmp(pixels.data(), expect.depth.radial.data.data(), pixels.size()) == 0);  // NaN, inf kept
      const auto& cloud = back.messages["/curvestereo/points"][size_t(f)];
      Cdr c{cloud.data(), cloud.size()};
      c.get<int32_t>(), c.get<uint32_t>(), c.str();
      CHECK(c.get<uint32_t>() == uint32_t(h));
      CHECK(c.get<uint32_t>() == uint32_t(w));
      REQUIRE(c.get<uint32_t>() == 3);
      for (const char* name : {"x", "y", "z"}) {
        CHECK(c.str() == name);
        c.get<uint32_t>();
        CHECK(c.get<uint8_t>() == 7);  // FLOAT32
        CHECK(c.get<uint32_t>() == 1);
      }
      c.get<uint8_t>();
      CHECK(c.get<uint32_t>() == 12);
      CHECK(c.get<uint32_t>() == uint32_t(12 * w));
      const std::vector<uint8_t> xyz = c.bytes();
      REQUIRE(xyz.size() == size_t(12 * w * h));
      float z3;  // pixel 3: confidence 0.3 < 0.5, so NaN; pixel 5: 0.5, kept
      std::memcpy(&z3, xyz.data() + 12 * 3 + 8, 4);
      CHECK(std::isnan(z3));
      float z5;
      std::memcpy(&z5, xyz.data() + 12 * 5 + 8, 4);
      CHECK(z5 == expect.depth.points.data[5].z);
    }
    const auto& info = back.messages["/curvestereo/camera_info"][0];
    Cdr i{info.data(), info.size()};
    i.get<int32_t>(), i.get<uint32_t>(), i.str();
    CHECK(i.get<uint32_t>() == uint32_t(h));
    CHECK(i.get<uint32_t>() == uint32_t(w));
    CHECK(i.str() == "equidistant");
    REQUIRE(i.get<uint32_t>() == 4);
    CHECK(i.get<double>() == 0.01);
    i.get<double>(), i.get<double>(), i.get<double>();
    CHECK(i.get<double>() == 10.0);  // K[0] = fx
  }
}

TEST_CASE("MCAP files written here read back in Foxglove's @mcap/core (node; skipped without it or npm)") {
  if (std::system("command -v node >/dev/null 2>&1 && command -v npm >/dev/null 2>&1") != 0) {
    MESSAGE("skipped: node and npm are not both on the PATH");
    return;
  }
  const char* home = std::getenv("HOME");
  const fs::path cache = fs::path(home ? home : "/tmp") / ".cache" / "curvestereo-npm";
  fs::create_directories(cache);
  if (!fs::exists(cache / "node_modules" / "@mcap" / "core") &&
      std::system(
          ("cd '" + cache.string() + "' && npm install --silent --no-audit --no-fund @mcap/core@2 " + ">/dev/null 2>&1")
              .c_str()) != 0) {
    MESSAGE("skipped: npm could not install @mcap/core (no network?)");
    return;
  }
  const fs::path dir = cs::test::tempDir("depth_log_node");
  const std::string path = (dir / "depth.mcap").string();
  {
    cs::DepthLogOptions o;
    o.compression = "none";  // @mcap/core brings no zstd or lz4 decoder of its own
    o.chunkBytes = 700;
    cs::DepthLogWriter writer(path, smallRig(7, 4), o);
    for (int f = 0; f < 4; ++f) writer.write(5'000'000'000 + f * 1'000'000, fakeResult(7, 4, f));
    writer.close();
  }
  // The indexed reader checks the footer, summary CRC and indexes; the stream reader every
  // record, the chunks' CRCs and the data section's CRC.
  const std::string script = R"(
const fs = require('fs');
const { McapIndexedReader, McapStreamReader } = require('@mcap/core');
const bytes = fs.readFileSync(process.argv[2]);
(async () => {
  const reader = await McapIndexedReader.Initialize({ readable: {
    size: async () => BigInt(bytes.length),
    read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)) } });
  const counts = {};
  for await (const m of reader.readMessages()) {
    const topic = reader.channelsById.get(m.channelId).topic;
    counts[topic] = (counts[topic] || 0) + 1;
  }
  const stream = new McapStreamReader({ validateCrcs: true });
  stream.append(bytes);
  let records = 0, messages = 0, end = false;
  for (let r; (r = stream.nextRecord()); ) { records++; if (r.type === 'Message') messages++; if (r.type === 'Footer') end = true; }
  const schemas = [...reader.schemasById.values()].map((s) => s.name + ':' + s.encoding).sort().join(',');
  console.log(JSON.stringify({ counts, messages, end, done: stream.done(), profile: reader.header.profile, schemas }));
})().catch((e) => { console.log('ERROR ' + e.message); process.exit(1); });
)";
  std::ofstream(dir / "check.js") << script;
  const std::string out = (dir / "out.txt").string();
  const int rc = std::system(("NODE_PATH='" + (cache / "node_modules").string() + "' node '" +
                              (dir / "check.js").string() + "' '" + path + "' > '" + out + "' 2>&1")
                                 .c_str());
  std::ifstream f(out);
  const std::string result((std::istreambuf_iterator<char>(f)), {});
  CAPTURE(result);
  CHECK(rc == 0);
  CHECK(result.find("\"/curvestereo/depth\":4") != std::string::npos);
  CHECK(result.find("\"/curvestereo/points\":4") != std::string::npos);
  CHECK(result.find("\"messages\":16") != std::string::npos);
  CHECK(result.find("\"end\":true") != std::string::npos);
  CHECK(result.find("\"profile\":\"ros2\"") != std::string::npos);
  CHECK(result.find("sensor_msgs/msg/PointCloud2:ros2msg") != std::string::npos);
}

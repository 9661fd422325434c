// Depth logs (DepthLogWriter) and image logs (writeImageLog) in MCAP with ros2msg schemas:
// the sensor_msgs messages serialised as ROS 2 CDR (mcap_writer.hpp).
#include <cmath>
#include <fstream>
#include <sstream>

#include "curvestereo/image_io.hpp"
#include "curvestereo/log.hpp"
#include "log_reader.hpp"
#include "mcap_writer.hpp"

namespace cs {
namespace {

// ros2msg schemas: the message's definition, then each type it uses after a line of '='.
constexpr const char* kSeparator =
    "\n================================================================================\n";
constexpr const char* kHeaderDef = "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n";
constexpr const char* kTimeDef = "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n";

std::string withHeader(const std::string& body, const std::string& more = "") {
  return body + kSeparator + kHeaderDef + kSeparator + kTimeDef + more;
}

const std::string& imageSchema() {
  static const std::string s = withHeader(
      "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\n"
      "uint8[] data\n");
  return s;
}
const std::string& compressedImageSchema() {
  static const std::string s = withHeader("std_msgs/Header header\nstring format\nuint8[] data\n");
  return s;
}
const std::string& cameraInfoSchema() {
  static const std::string s = withHeader(
      "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\nfloat64[9] k\n"
      "float64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\nsensor_msgs/RegionOfInterest roi\n",
      std::string(kSeparator) +
          "MSG: sensor_msgs/RegionOfInterest\nuint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\n"
          "bool do_rectify\n");
  return s;
}
const std::string& pointCloudSchema() {
  static const std::string s = withHeader(
      "std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\nbool is_bigendian\n"
      "uint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n",
      std::string(kSeparator) +
          "MSG: sensor_msgs/PointField\nuint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\n"
          "uint8 UINT32=6\nuint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 "
          "count\n");
  return s;
}

std::vector<uint8_t> floatImage(int64_t stampNs, const std::string& frameId, const ImageF& img) {
  CdrBuffer b;
  b.header(stampNs, frameId);
  b.u32(uint32_t(img.height));
  b.u32(uint32_t(img.width));
  b.str("32FC1");
  b.u8(0);
  b.u32(uint32_t(img.width * 4));
  b.bytes(img.data.data(), img.size() * sizeof(float));
  return b.data();
}

// K, D and the model of a camera: ROS's "equidistant" is Kannala-Brandt's k1..k4; other
// models keep curvestereo's name with their parameters after fx fy cx cy as D.
void cameraInfo(CdrBuffer& b, int width, int height, const std::string& model, const std::vector<double>& d, double fx,
                double fy, double cx, double cy) {
  b.u32(uint32_t(height));
  b.u32(uint32_t(width));
  b.str(model);
  b.u32(uint32_t(d.size()));
  for (double v : d) b.f64(v);
  for (double v : {fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0}) b.f64(v);
  for (double v : {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}) b.f64(v);
  for (double v : {fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0}) b.f64(v);
  b.u32(0), b.u32(0);                      // binning
  b.u32(0), b.u32(0), b.u32(0), b.u32(0);  // roi: the whole image
  b.u8(0);
}

std::vector<uint8_t> fisheyeInfo(int64_t stampNs, const std::string& frameId, const Camera& cam) {
  CdrBuffer b;
  b.header(stampNs, frameId);
  const std::vector<double>& p = cam.params;
  const std::vector<double> d(p.begin() + 4, p.end());
  cameraInfo(b, cam.width, cam.height, cam.model == CameraModel::KannalaBrandt4 ? "equidistant" : cam.modelName(), d,
             p[0], p[1], p[2], p[3]);
  return b.data();
}

std::vector<uint8_t> pinholeInfo(int64_t stampNs, const std::string& frameId, const PinholeView& v) {
  CdrBuffer b;
  b.header(stampNs, frameId);
  cameraInfo(b, v.width, v.height, "plumb_bob", {0, 0, 0, 0, 0}, v.fx, v.fy, v.cx, v.cy);
  return b.data();
}

// Organised x y z float32 (12 bytes a point), NaN where there is no point.
std::vector<uint8_t> pointCloud(int64_t stampNs, const std::string& frameId, const DepthResult& r,
                                float minConfidence) {
  const Image<Point3f>& pts = r.depth.points;
  std::vector<float> xyz(pts.size() * 3);
  for (size_t i = 0; i < pts.size(); ++i) {
    const bool keep = r.confidence.empty() || r.confidence.data[i] >= minConfidence;
    xyz[3 * i] = keep ? pts.data[i].x : NAN;
    xyz[3 * i + 1] = keep ? pts.data[i].y : NAN;
    xyz[3 * i + 2] = keep ? pts.data[i].z : NAN;
  }
  CdrBuffer b;
  b.header(stampNs, frameId);
  b.u32(uint32_t(pts.height));
  b.u32(uint32_t(pts.width));
  b.u32(3);
  for (uint32_t k = 0; k < 3; ++k) {
    b.str(std::string(1, char('x' + k)));
    b.u32(4 * k);
    b.u8(7);  // FLOAT32
    b.u32(1);
  }
  b.u8(0);  // is_bigendian
  b.u32(12);
  b.u32(uint32_t(12 * pts.width));
  b.bytes(xyz.data(), xyz.size() * sizeof(float));
  b.u8(0);  // is_dense: NaN points are kept in the grid
  return b.data();
}

std::string readBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error("cannot read '" + path + "'");
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

// sensor_msgs/Image mono8 (or mono16 for a 16-bit PNG) of an image file: the PNG's samples,
// recovered exactly from readPngGray's v / 255 (or v / 65535).
std::vector<uint8_t> rawImageMessage(int64_t stampNs, const std::string& frameId, const std::string& path) {
  PngFormat format;
  const ImageF img = readPngGray(path, &format);
  const bool wide = format.bitDepth == 16;
  const double scale = wide ? 65535.0 : 255.0;
  std::vector<uint8_t> pixels(img.size() * (wide ? 2 : 1));
  for (size_t i = 0; i < img.size(); ++i) {
    const long v = std::lround(double(img.data[i]) * scale);
    if (wide)
      pixels[2 * i] = uint8_t(v & 0xff), pixels[2 * i + 1] = uint8_t(v >> 8);
    else
      pixels[i] = uint8_t(v);
  }
  CdrBuffer b;
  b.header(stampNs, frameId);
  b.u32(uint32_t(img.height));
  b.u32(uint32_t(img.width));
  b.str(wide ? "mono16" : "mono8");
  b.u8(0);
  b.u32(uint32_t(img.width * (wide ? 2 : 1)));
  b.bytes(pixels.data(), pixels.size());
  return b.data();
}

std::vector<uint8_t> pngMessage(int64_t stampNs, const std::string& frameId, const std::string& path) {
  const std::string bytes = readBytes(path);
  if (bytes.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0) throw Error("'" + path + "' is not a PNG file");
  CdrBuffer b;
  b.header(stampNs, frameId);
  b.str("png");
  b.bytes(bytes.data(), bytes.size());
  return b.data();
}

}  // namespace

DepthLogWriter::DepthLogWriter(const std::string& path, const Rig& rig, const DepthLogOptions& options)
    : rig_(rig), options_(options) {
  mcap_ = std::make_unique<McapWriter>(path, options.compression, options.chunkBytes);
  const uint16_t image = mcap_->addSchema("sensor_msgs/msg/Image", "ros2msg", imageSchema());
  const uint16_t info = mcap_->addSchema("sensor_msgs/msg/CameraInfo", "ros2msg", cameraInfoSchema());
  const uint16_t cloud = mcap_->addSchema("sensor_msgs/msg/PointCloud2", "ros2msg", pointCloudSchema());
  const std::string& p = options.topicPrefix;
  depth_ = mcap_->addChannel(image, p + "/depth", "cdr");
  info_ = mcap_->addChannel(info, p + "/camera_info", "cdr");
  points_ = mcap_->addChannel(cloud, p + "/points", "cdr");
  confidence_ = mcap_->addChannel(image, p + "/confidence", "cdr");
  if (options.pinhole) {
    pinholeDepth_ = mcap_->addChannel(image, p + "/depth_pinhole", "cdr");
    pinholeInfo_ = mcap_->addChannel(info, p + "/depth_pinhole/camera_info", "cdr");
  }
}

DepthLogWriter::~DepthLogWriter() = default;  // McapWriter's destructor closes

void DepthLogWriter::write(int64_t stampNs, const DepthResult& r) {
  if (stampNs < 0) throw Error("depth log: a negative timestamp (" + std::to_string(stampNs) + " ns)");
  const std::string& id = options_.frameId;
  const uint64_t t = uint64_t(stampNs);
  mcap_->write(depth_, t, floatImage(stampNs, id, r.depth.radial));
  mcap_->write(info_, t, fisheyeInfo(stampNs, id, rig_.cam0));
  mcap_->write(points_, t, pointCloud(stampNs, id, r, options_.minConfidence));
  if (!r.confidence.empty()) mcap_->write(confidence_, t, floatImage(stampNs, id, r.confidence));
  if (options_.pinhole) {
    const ImageF z = pinholeDepth(rig_.cam0, r.depth.radial, options_.pinholeView, options_.sampling);
    mcap_->write(pinholeDepth_, t, floatImage(stampNs, id, z));
    mcap_->write(pinholeInfo_, t, pinholeInfo(stampNs, id, options_.pinholeView));
  }
  ++frames_;
}

void DepthLogWriter::close() { mcap_->close(); }

void writeImageLog(const std::string& path, const Sequence& sequence, const ImageLogOptions& options) {
  if (options.format != "raw" && options.format != "png")
    throw Error("image log format must be raw or png, got '" + logio::shown(options.format) + "'");
  if (options.leftTopic == options.rightTopic) throw Error("the left and right topics are the same");
  McapWriter mcap(path, options.compression, options.chunkBytes);
  const bool png = options.format == "png";
  const uint16_t schema = png ? mcap.addSchema("sensor_msgs/msg/CompressedImage", "ros2msg", compressedImageSchema())
                              : mcap.addSchema("sensor_msgs/msg/Image", "ros2msg", imageSchema());
  const uint16_t left = mcap.addChannel(schema, options.leftTopic, "cdr");
  const uint16_t right = mcap.addChannel(schema, options.rightTopic, "cdr");
  for (const SequenceFrame& f : sequence.frames()) {
    if (f.timestampNs < 0) throw Error("image log: frame timestamps must be >= 0");
    const auto message = [&](const std::string& file, const char* frameId) {
      return png ? pngMessage(f.timestampNs, frameId, file) : rawImageMessage(f.timestampNs, frameId, file);
    };
    mcap.write(left, uint64_t(f.timestampNs), message(f.leftPath, "cam0"));
    mcap.write(right, uint64_t(f.timestampNs), message(f.rightPath, "cam1"));
  }
  mcap.close();
}

}  // namespace cs

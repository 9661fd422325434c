// A log's stereo frames as a cs::Sequence (Sequence::openLog), and logInfo: the readers of
// log_reader.hpp, the image messages' stamps and encodings, and the pairing of the two topics
// as ASL folders pair their cameras (sequence_pairing.hpp).
#include <algorithm>
#include <cmath>

#include "curvestereo/log.hpp"
#include "log_reader.hpp"
#include "sequence_pairing.hpp"

namespace cs {

struct Sequence::LogFrames {
  std::unique_ptr<logio::Reader> reader;
  std::string path;
  struct Side {
    std::string topic;
    uint32_t channel = 0;
    logio::ImageKind kind = logio::ImageKind::None;
    bool cdr = true;
  } left, right;
  struct Message {
    logio::MessageRef ref;
    uint64_t index = 0;  // among its topic's messages
  };
  std::vector<std::pair<Message, Message>> frames;
};

struct Sequence::Stamped {
  int64_t stampNs;
  LogFrames::Message message;
};

namespace {

using logio::shown;
using Side = Sequence::LogFrames::Side;
using Stamped = Sequence::Stamped;

std::string imageTopics(const logio::Reader& reader) {
  std::string list;
  for (const logio::Channel& c : reader.channels())
    if (logio::imageKind(c.type) != logio::ImageKind::None) list += (list.empty() ? "" : ", ") + shown(c.topic);
  return list.empty() ? "none" : list;
}

Side findTopic(const logio::Reader& reader, const std::string& topic, const std::string& path) {
  const auto& channels = reader.channels();
  const auto it = std::find_if(channels.begin(), channels.end(), [&](const auto& c) { return c.topic == topic; });
  if (it == channels.end())
    throw Error("log '" + path + "' has no topic '" + shown(topic) + "' (its image topics: " + imageTopics(reader) +
                ")");
  Side side{topic, uint32_t(it - channels.begin()), logio::imageKind(it->type), it->cdr()};
  if (side.kind == logio::ImageKind::None)
    throw Error("topic '" + topic + "' of log '" + path + "' is of type '" + shown(it->type) +
                "', not sensor_msgs/Image or sensor_msgs/CompressedImage");
  if (it->encoding != "cdr" && it->encoding != "ros1")
    throw Error("topic '" + topic + "' of log '" + path + "' is serialised as '" + shown(it->encoding) +
                "' (ROS 2 CDR or ROS 1 are read)");
  return side;
}

std::string messageName(const std::string& path, const std::string& topic, uint64_t index, int64_t logNs) {
  return "log '" + path + "', topic '" + topic + "', message " + std::to_string(index) + " (logged at " +
         std::to_string(logNs) + " ns)";
}

// One message at opening: its stamp, and an encoding this reads.
Stamped stampOf(const logio::MessageRef& ref, const uint8_t* p, size_t n, const Side& side, uint64_t index,
                const std::string& path) {
  try {
    const std::string encoding = logio::imageEncoding(p, n, side.cdr, side.kind);
    if (!logio::supportedEncoding(encoding, side.kind))
      throw Error(side.kind == logio::ImageKind::Raw
                      ? "unsupported encoding '" + shown(encoding) + "' (mono8, mono16, rgb8 and bgr8 are read)"
                      : "unsupported CompressedImage format '" + shown(encoding) + "' (png and jpeg are read)");
    return Stamped{logio::headerStampNs(p, n, side.cdr), {ref, index}};
  } catch (const Error& e) {
    throw Error(messageName(path, side.topic, index, ref.logTimeNs) + ": " + e.what());
  }
}

}  // namespace

Sequence Sequence::openLog(const std::string& path, const std::string& leftTopic, const std::string& rightTopic,
                           const SequenceOptions& options) {
  detail::checkTolerances(options);
  if (leftTopic == rightTopic) throw Error("the left and right topics are the same ('" + shown(leftTopic) + "')");
  auto log = std::make_shared<LogFrames>();
  log->path = path;
  log->reader = logio::openReader(path);
  logio::Reader& reader = *log->reader;
  // An indexed log knows its channels now and skips the others' chunks; one without an index
  // declares them on the way (inside chunks), so it is scanned whole.
  std::vector<bool> wanted;
  const auto& channels = reader.channels();
  const auto has = [&](const std::string& t) {
    return std::any_of(channels.begin(), channels.end(), [&](const auto& c) { return c.topic == t; });
  };
  if (has(leftTopic) && has(rightTopic)) {
    wanted.assign(channels.size(), false);
    for (size_t c = 0; c < channels.size(); ++c)
      wanted[c] = channels[c].topic == leftTopic || channels[c].topic == rightTopic;
  }
  std::vector<Stamped> left, right;
  reader.scan(wanted, [&](const logio::MessageRef& ref, const uint8_t* p, size_t n) {
    const std::string& topic = channels[ref.channel].topic;
    const bool isLeft = topic == leftTopic;
    if (!isLeft && topic != rightTopic) return;
    Side& side = isLeft ? log->left : log->right;
    if (side.topic.empty()) side = findTopic(reader, topic, path);  // its type checked once
    std::vector<Stamped>& list = isLeft ? left : right;
    list.push_back(stampOf(ref, p, n, side, list.size(), path));
  });
  log->left = findTopic(reader, leftTopic, path);  // a missing topic is named here
  log->right = findTopic(reader, rightTopic, path);
  Sequence seq;
  seq.kind_ = reader.format();
  if (!reader.cut().empty()) seq.warnings_.push_back(reader.cut());
  pairLogFrames(seq, *log, left, right, options.pairToleranceMs);
  seq.log_ = std::move(log);
  if (!options.poses.empty()) seq.attachPoses(options.poses, options.poseToleranceMs);
  return seq;
}

void Sequence::pairLogFrames(Sequence& seq, LogFrames& log, std::vector<Stamped>& left, std::vector<Stamped>& right,
                             double toleranceMs) {
  const auto byStamp = [](const Stamped& a, const Stamped& b) { return a.stampNs < b.stampNs; };
  std::stable_sort(left.begin(), left.end(), byStamp);
  std::stable_sort(right.begin(), right.end(), byStamp);
  std::vector<int64_t> leftNs, rightNs;
  for (const Stamped& s : left) leftNs.push_back(s.stampNs);
  for (const Stamped& s : right) rightNs.push_back(s.stampNs);
  const detail::TimePairs paired = detail::pairByTime(leftNs, rightNs, toleranceMs);
  const auto name = [&](const std::string& topic, const Stamped& s) {
    return log.path + ":" + topic + "#" + std::to_string(s.message.index);
  };
  for (const auto& [i, j] : paired.pairs) {
    SequenceFrame f;
    f.timestampNs = left[i].stampNs;
    f.leftPath = name(log.left.topic, left[i]);
    f.rightPath = name(log.right.topic, right[j]);
    seq.frames_.push_back(std::move(f));
    log.frames.emplace_back(left[i].message, right[j].message);
  }
  const auto alone = [&](const std::string& topic, const Stamped& s, const std::string& other) {
    seq.warnings_.push_back(topic + " message " + std::to_string(s.message.index) + " (stamp " +
                            std::to_string(s.stampNs) + " ns): no " + other + " message within " +
                            detail::msText(toleranceMs));
  };
  for (size_t i : paired.leftAlone) alone(log.left.topic, left[i], log.right.topic);
  for (size_t j : paired.rightAlone) alone(log.right.topic, right[j], log.left.topic);
  seq.unpaired_ = paired.leftAlone.size() + paired.rightAlone.size();
  if (seq.frames_.empty())
    throw Error("log '" + log.path + "': no stereo frames ('" + log.left.topic + "' has " +
                std::to_string(left.size()) + " messages, '" + log.right.topic + "' " + std::to_string(right.size()) +
                ", none paired within " + detail::msText(toleranceMs) + ")" +
                (log.reader->cut().empty() ? "" : "; " + log.reader->cut()));
}

void Sequence::loadLog(size_t i, ImageF& left, ImageF& right) const {
  const LogFrames& log = *log_;
  const std::string frame = "frame " + std::to_string(i) + " (t " + std::to_string(frames_[i].timestampNs) + " ns)";
  const auto decode = [&](const LogFrames::Side& side, const LogFrames::Message& m, ImageF& out) {
    try {
      log.reader->read(m.ref, [&](const uint8_t* p, size_t n) { logio::decodeImage(p, n, side.cdr, side.kind, out); });
    } catch (const Error& e) {
      throw Error(frame + ", " + messageName(log.path, side.topic, m.index, m.ref.logTimeNs) + ": " + e.what());
    }
  };
  decode(log.left, log.frames[i].first, left);
  decode(log.right, log.frames[i].second, right);
  if (left.width != right.width || left.height != right.height)
    throw Error(frame + " of log '" + log.path + "': the left image is " + std::to_string(left.width) + "x" +
                std::to_string(left.height) + " but the right one " + std::to_string(right.width) + "x" +
                std::to_string(right.height));
}

LogInfo logInfo(const std::string& path) {
  const std::unique_ptr<logio::Reader> reader = logio::openReader(path);
  reader->keepChunks(false);
  reader->scan({}, [](const logio::MessageRef&, const uint8_t*, size_t) {});
  LogInfo info;
  info.format = reader->format();
  info.cut = reader->cut();
  for (const logio::Channel& c : reader->channels()) {
    info.topics.push_back(LogTopic{c.topic, c.type, c.encoding, c.count, c.firstNs, c.lastNs});
    if (!c.count) continue;
    if (!info.messages || c.firstNs < info.startNs) info.startNs = c.firstNs;
    if (!info.messages || c.lastNs > info.endNs) info.endNs = c.lastNs;
    info.messages += c.count;
  }
  return info;
}

}  // namespace cs

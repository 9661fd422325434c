// curvestereo log info FILE: a recorded log's topics, types, message counts and time range.
// curvestereo log write --sequence SRC -o FILE.mcap [--topics LEFT,RIGHT] [--format raw|png]
//                       [--compression zstd|lz4|none]: a sequence's images as an MCAP log.
#include <cinttypes>
#include <cstdio>

#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/log.hpp"

namespace cs::cli {

namespace {

std::string seconds(int64_t ns) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.3f s", double(ns) * 1e-9);
  return buf;
}

int logInfoCommand(const Args& args) {
  if (args.positional().size() != 2) throw UsageError("log info needs exactly one log: log info FILE");
  const std::string path = args.positional()[1];
  const LogInfo info = logInfo(path);
  std::printf("%s: %s\n", path.c_str(), info.format.c_str());
  if (info.messages)
    std::printf("%" PRIu64 " messages from %" PRId64 " to %" PRId64 " ns (%s)\n", info.messages, info.startNs,
                info.endNs, seconds(info.endNs - info.startNs).c_str());
  else
    std::printf("no messages\n");
  for (const LogTopic& t : info.topics)
    std::printf("  %-40s %-34s %-4s %6" PRIu64 " messages%s\n", t.name.c_str(), t.type.c_str(), t.serialisation.c_str(),
                t.messages,
                t.messages > 1
                    ? ("  " +
                       std::to_string(int64_t(
                           double(t.messages - 1) * 1e9 / std::max<double>(1, double(t.lastNs - t.firstNs)) + 0.5)) +
                       " Hz")
                          .c_str()
                    : "");
  if (!info.cut.empty()) std::fprintf(stderr, "curvestereo: warning: %s\n", info.cut.c_str());
  return 0;
}

int logWriteCommand(const Args& args) {
  if (args.positional().size() != 1) throw UsageError("log write takes no positional arguments");
  const std::string out = args.has("o") ? args.get("o", "") : args.require("output");
  ImageLogOptions options;
  if (args.has("topics")) {
    const std::string topics = args.get("topics", "");
    const size_t comma = topics.find(',');
    if (comma == std::string::npos || comma == 0 || comma + 1 == topics.size())
      throw UsageError("--topics expects LEFT,RIGHT, got '" + topics + "'");
    options.leftTopic = topics.substr(0, comma);
    options.rightTopic = topics.substr(comma + 1);
  }
  options.format = args.get("format", options.format);
  options.compression = args.get("compression", options.compression);
  const Sequence sequence = Sequence::open(args.require("sequence"));
  writeImageLog(out, sequence, options);
  std::printf("%zu stereo frames into %s (%s, topics %s and %s)\n", sequence.frames().size(), out.c_str(),
              options.format == "png" ? "sensor_msgs/CompressedImage png" : "sensor_msgs/Image",
              options.leftTopic.c_str(), options.rightTopic.c_str());
  return 0;
}

}  // namespace

int cmdLog(const Args& args) {
  args.allowOnly({"o", "output", "sequence", "topics", "format", "compression"});
  const std::string what = args.positional().empty() ? "" : args.positional()[0];
  if (what == "info") return logInfoCommand(args);
  if (what == "write") return logWriteCommand(args);
  throw UsageError("log needs info or write, got '" + what + "'");
}

}  // namespace cs::cli

// curvestereo log info FILE: a recorded log's topics, types, message counts and time range.
// curvestereo log info FILE --time-read --topics LEFT,RIGHT [--solve-ms S] [--read-threads N]:
//                       what opening the log as a sequence costs, reading (decoding) each
//                       frame in order, and the wait left with run's reading ahead.
// curvestereo log write --sequence SRC -o FILE.mcap [--topics LEFT,RIGHT] [--format raw|png]
//                       [--compression zstd|lz4|none]: a sequence's images as an MCAP log.
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <thread>
#include <tuple>

#include "commands.hpp"
#include "common.hpp"
#include "curvestereo/log.hpp"

namespace cs::cli {

namespace {

std::pair<std::string, std::string> topicPair(const std::string& topics) {
  const size_t comma = topics.find(',');
  if (comma == std::string::npos || comma == 0 || comma + 1 == topics.size() ||
      topics.find(',', comma + 1) != std::string::npos)
    throw UsageError("--topics expects LEFT,RIGHT, got '" + topics + "'");
  return {topics.substr(0, comma), topics.substr(comma + 1)};
}

std::string seconds(int64_t ns) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.3f s", double(ns) * 1e-9);
  return buf;
}

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// --time-read: the reading cost on this machine, the figure to hold against a frame's solve
// (run's summary says how much of it the solving thread still waits for).
int timeReadCommand(const Args& args, const std::string& path) {
  const auto [left, right] = topicPair(args.require("topics"));
  auto t0 = std::chrono::steady_clock::now();
  const Sequence sequence = Sequence::openLog(path, left, right);
  const double openMs = msSince(t0);
  ImageF l, r;
  t0 = std::chrono::steady_clock::now();
  const size_t n = sequence.frames().size();
  for (size_t i = 0; i < n; ++i) sequence.load(i, l, r);
  const double readMs = msSince(t0);
  std::printf("%s: %s; opened in %.1f ms; %zu frames (%dx%d) read in %.1f ms: %.2f ms a frame\n", path.c_str(),
              sequence.summary().c_str(), openMs, n, l.width, l.height, readMs, readMs / double(n));
  // Then as run reads them, ahead on background threads, against a solve of --solve-ms
  // (a GPU's, by default: the solving thread waits for the device meanwhile).
  const double solveMs = args.getDouble("solve-ms", 2.5);
  if (!(solveMs >= 0 && solveMs <= 60000)) throw UsageError("--solve-ms expects 0 to 60000 ms");
  SequenceReader reader(sequence, readThreads(args));
  size_t i = 0;
  while (reader.next(i, l, r)) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(solveMs));
  std::printf(
      "read ahead on %d thread%s against a %.2f ms solve: the solving thread waited %.1f ms for the first "
      "frame, %.3f ms a frame for the others (%.1f %% of the solve)\n",
      reader.threads(), reader.threads() == 1 ? "" : "s", solveMs, reader.firstWaitMs(),
      reader.waitedMs() / double(std::max<size_t>(n - 1, 1)),
      solveMs > 0 ? 100.0 * reader.waitedMs() / double(std::max<size_t>(n - 1, 1)) / solveMs : 0.0);
  return 0;
}

int logInfoCommand(const Args& args) {
  if (args.positional().size() != 2) throw UsageError("log info needs exactly one log: log info FILE");
  const std::string path = args.positional()[1];
  if (args.has("time-read")) return timeReadCommand(args, path);
  if (args.has("topics")) throw UsageError("--topics is for log info --time-read or log write");
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
  if (args.has("topics")) std::tie(options.leftTopic, options.rightTopic) = topicPair(args.get("topics", ""));
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
  args.allowOnly(
      {"o", "output", "sequence", "topics", "format", "compression", "time-read", "solve-ms", "read-threads"});
  for (const char* option : {"time-read", "solve-ms", "read-threads"})
    if (args.has(option) && (args.positional().empty() || args.positional()[0] != "info" || !args.has("time-read")))
      throw UsageError(std::string("--") + option + " is for log info --time-read");
  const std::string what = args.positional().empty() ? "" : args.positional()[0];
  if (what == "info") return logInfoCommand(args);
  if (what == "write") return logWriteCommand(args);
  throw UsageError("log needs info or write, got '" + what + "'");
}

}  // namespace cs::cli

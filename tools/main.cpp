// curvestereo: dense depth from a calibrated fisheye stereo pair, without rectification.
#include <cstdio>
#include <cstring>
#include <exception>
#include <set>
#include <string>

#include "commands.hpp"
#include "common.hpp"
#include "help.hpp"

int main(int argc, char** argv) {
  using namespace cs::cli;
  auto isHelp = [](const char* a) { return !std::strcmp(a, "--help") || !std::strcmp(a, "-h"); };
  if (argc < 2) {
    std::fputs(overviewHelp().c_str(), stderr);
    return 2;
  }
  const std::string command = argv[1];
  if (isHelp(argv[1]) || command == "help") {
    // `curvestereo help run` is `curvestereo run --help`.
    if (command == "help" && argc > 2) {
      const std::string text = commandHelp(argv[2]);
      if (text.empty()) {
        std::fprintf(stderr, "curvestereo: error: unknown command '%s' (try --help)\n", argv[2]);
        return 2;
      }
      std::fputs(text.c_str(), stdout);
      return 0;
    }
    std::fputs(overviewHelp().c_str(), stdout);
    return 0;
  }
  if (command == "--version" || command == "version") {
    std::printf("%s\n", versionText().c_str());
    return 0;
  }
  const std::string help = commandHelp(command);
  if (help.empty()) {
    std::fprintf(stderr, "curvestereo: error: unknown command '%s' (try --help)\n", command.c_str());
    return 2;
  }
  for (int i = 2; i < argc; ++i)
    if (isHelp(argv[i])) {
      std::fputs(help.c_str(), stdout);
      return 0;
    }
  try {
    // "-o DIR" is accepted as a short form of --o / --output.
    std::vector<char*> rest;
    std::string dashO = "--o";
    for (int i = 2; i < argc; ++i) rest.push_back(!std::strcmp(argv[i], "-o") ? dashO.data() : argv[i]);
    // Options without a value; --sequence is one for synth only (run and bench take a source).
    std::set<std::string> flags = {"quiet", "scale-intrinsics", "cold",         "compare",
                                   "blind", "serial",           "whole-images", "one-way"};
    if (command == "synth") flags.insert("sequence");
    if (command == "log") flags.insert("time-read");
    if (command == "run") flags.insert("rig");
    const cs::cli::Args args(int(rest.size()), rest.data(), flags);
    if (command == "run") return cs::cli::cmdRun(args);
    if (command == "demo") return cs::cli::cmdDemo(args);
    if (command == "synth") return cs::cli::cmdSynth(args);
    if (command == "eval") return cs::cli::cmdEval(args);
    if (command == "fields") return cs::cli::cmdFields(args);
    if (command == "bench") return cs::cli::cmdBench(args);
    if (command == "calib") return cs::cli::cmdCalib(args);
    if (command == "log") return cs::cli::cmdLog(args);
    return 2;  // not reached: commandHelp() knows exactly these commands
  } catch (const UsageError& e) {
    std::fprintf(stderr, "curvestereo: error: %s (see 'curvestereo %s --help')\n", e.what(), command.c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "curvestereo: error: %s\n", e.what());
    return 1;
  }
}

// Running the built `curvestereo` binary from a test (build/tools/curvestereo beside
// build/tests/<test>), for the suites that check the command line end to end.
#pragma once
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <doctest/doctest.h>

namespace cs::test {

inline std::filesystem::path cliPath() {
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe");
  return self.parent_path().parent_path() / "tools" / "curvestereo";
}

inline std::string readFile(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

struct CliOutcome {
  int exitCode = -1;
  std::string out, err;
};

// Runs `curvestereo ARGS` in dir (ARGS as a shell would split them).
inline CliOutcome runCli(const std::filesystem::path& dir, const std::string& args) {
  const std::string cmd =
      "cd '" + dir.string() + "' && '" + cliPath().string() + "' " + args + " > stdout.txt 2> stderr.txt";
  const int status = std::system(cmd.c_str());
  CliOutcome o;
  o.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  o.out = readFile(dir / "stdout.txt");
  o.err = readFile(dir / "stderr.txt");
  return o;
}

// A refusal: exit 1 (2 for a malformed command line) and one stderr line
// "curvestereo: error: ..." containing needle.
inline void checkRefused(const CliOutcome& o, const std::string& needle, int exitCode = 1) {
  CAPTURE(o.err);
  CHECK(o.exitCode == exitCode);
  CHECK(o.err.rfind("curvestereo: error: ", 0) == 0);
  CHECK(std::count(o.err.begin(), o.err.end(), '\n') == 1);
  CHECK(o.err.find(needle) != std::string::npos);
}

}  // namespace cs::test

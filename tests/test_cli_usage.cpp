// The command line's help, version and exit statuses: each command's --help is its own, the
// version is the project's, and a malformed command line exits 2 with one error line while
// an error in the inputs exits 1.
#include <algorithm>
#include <filesystem>
#include <regex>
#include <string>

#include "cli_util.hpp"
#include "test_util.hpp"

namespace fs = std::filesystem;
using cs::test::CliOutcome;
using cs::test::runCli;

namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// A malformed command line: exit 2, one stderr line, pointing to the command's help.
void checkUsageError(const CliOutcome& o, const std::string& needle) {
  CAPTURE(o.err);
  CHECK(o.exitCode == 2);
  CHECK(o.err.rfind("curvestereo: error: ", 0) == 0);
  CHECK(std::count(o.err.begin(), o.err.end(), '\n') == 1);
  CHECK(contains(o.err, needle));
}

}  // namespace

TEST_CASE("every command's --help is its own, on stdout, exit 0") {
  const fs::path dir = cs::test::tempDir("cli_usage_help");
  for (const std::string command : {"run", "demo", "synth", "eval", "bench", "fields", "calib"}) {
    CAPTURE(command);
    for (const std::string& form : {command + " --help", command + " -h", "help " + command}) {
      const CliOutcome o = runCli(dir, form);
      CHECK(o.exitCode == 0);
      CHECK(o.err.empty());
      CHECK(o.out.rfind("usage: curvestereo " + command, 0) == 0);
    }
  }
  // The options once missing from the help.
  const std::string eval = runCli(dir, "eval --help").out;
  CHECK(contains(eval, "--methods"));
  CHECK(contains(eval, "--sweep warps="));
  CHECK(contains(eval, "--warps-list"));
  CHECK(contains(runCli(dir, "bench --help").out, "--outputs depth|all"));
  CHECK(contains(runCli(dir, "run --help").out, "--warps-taper"));  // the solver's options
  CHECK(contains(runCli(dir, "synth --help").out, "--camera none|t265"));
  CHECK_FALSE(contains(runCli(dir, "calib --help").out, "--warps"));

  const CliOutcome overview = runCli(dir, "--help");
  CHECK(overview.exitCode == 0);
  for (const std::string command : {"run", "demo", "synth", "eval", "bench", "fields", "calib"})
    CHECK(contains(overview.out, "  " + command + " "));
}

TEST_CASE("--version prints the project's version") {
  const fs::path dir = cs::test::tempDir("cli_usage_version");
  const CliOutcome o = runCli(dir, "--version");
  CHECK(o.exitCode == 0);
  CHECK(std::regex_match(o.out, std::regex("curvestereo [0-9]+\\.[0-9]+\\.[0-9]+\n")));
}

TEST_CASE("a malformed command line exits 2, an error in the inputs 1") {
  const fs::path dir = cs::test::tempDir("cli_usage_exit");
  const CliOutcome none = runCli(dir, "");
  CHECK(none.exitCode == 2);
  CHECK(contains(none.err, "usage: curvestereo"));
  checkUsageError(runCli(dir, "frobnicate"), "unknown command 'frobnicate'");
  checkUsageError(runCli(dir, "run"), "run needs exactly two images");
  checkUsageError(runCli(dir, "run --calib c.yaml l.png r.png"), "missing required option --output");
  checkUsageError(runCli(dir, "run --calib c.yaml l.png r.png -o out --frobnicate 1"), "unknown option --frobnicate");
  checkUsageError(runCli(dir, "run --calib"), "option --calib needs a value");
  checkUsageError(runCli(dir, "run --calib c.yaml l.png r.png -o out --warps many"), "expects an integer");
  checkUsageError(runCli(dir, "eval"), "eval needs at least one pair folder");
  checkUsageError(runCli(dir, "synth"), "missing output folder");
  checkUsageError(runCli(dir, "calib"), "sub-command");
  checkUsageError(runCli(dir, "fields -o out"), "missing required option --calib");
  CHECK(contains(runCli(dir, "run").err, "(see 'curvestereo run --help')"));

  // The inputs: exit 1.
  const CliOutcome missing = runCli(dir, "run --calib none.yaml l.png r.png -o out");
  CHECK(missing.exitCode == 1);
  CHECK((contains(missing.err, "none.yaml") || contains(missing.err, "l.png")));  // the first missing input
  CHECK(runCli(dir, "synth -o s --size 8").exitCode == 1);  // a value out of range
}

// The help texts of `curvestereo`: one per sub-command, and the overview that lists them.
#pragma once
#include <string>

namespace cs::cli {

// The overview: every command in one line, how to get a command's own help.
std::string overviewHelp();

// A command's own help (its usage lines, its options and, for the solving commands, the
// solver options); empty when `command` is not a command.
std::string commandHelp(const std::string& command);

// "curvestereo 0.1.0" (the CMake project version).
std::string versionText();

}  // namespace cs::cli

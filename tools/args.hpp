// A minimal command-line parser shared by the sub-commands:
//   --name value | --name=value | --flag | positional...
#pragma once
#include <map>
#include <set>
#include <string>
#include <vector>

#include "curvestereo/image.hpp"

namespace cs::cli {

// A malformed command line: an unknown command or option, a missing option or argument, an
// option without its value or with a value that is not a number. main() prints it as one
// line, like every cs::Error, and exits 2 (1 for the other errors).
class UsageError : public Error {
 public:
  using Error::Error;
};

class Args {
 public:
  // flags: option names that take no value (e.g. {"help", "quiet"}).
  Args(int argc, char** argv, const std::set<std::string>& flags);

  bool has(const std::string& name) const { return options_.count(name) > 0 || flags_.count(name) > 0; }
  std::string get(const std::string& name, const std::string& fallback) const;
  std::string require(const std::string& name) const;  // throws UsageError "missing --name"
  double getDouble(const std::string& name, double fallback) const;
  int getInt(const std::string& name, int fallback) const;
  const std::vector<std::string>& positional() const { return positional_; }
  // Throws UsageError naming the first option not in `known` (catches typos).
  void allowOnly(const std::set<std::string>& known) const;

 private:
  std::map<std::string, std::string> options_;
  std::set<std::string> flags_;
  std::vector<std::string> positional_;
};

}  // namespace cs::cli

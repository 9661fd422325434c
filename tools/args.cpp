#include "args.hpp"

#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>

namespace cs::cli {

Args::Args(int argc, char** argv, const std::set<std::string>& flags) {
  for (int i = 0; i < argc; ++i) {
    std::string a = argv[i];
    if (a.size() > 2 && a.compare(0, 2, "--") == 0) {
      std::string name = a.substr(2);
      auto eq = name.find('=');
      if (eq != std::string::npos) {
        options_[name.substr(0, eq)] = name.substr(eq + 1);
      } else if (flags.count(name)) {
        flags_.insert(name);
      } else {
        if (i + 1 >= argc) throw UsageError("option --" + name + " needs a value");
        options_[name] = argv[++i];
      }
    } else {
      positional_.push_back(a);
    }
  }
}

std::string Args::get(const std::string& name, const std::string& fallback) const {
  auto it = options_.find(name);
  return it == options_.end() ? fallback : it->second;
}

std::string Args::require(const std::string& name) const {
  auto it = options_.find(name);
  if (it == options_.end()) throw UsageError("missing required option --" + name);
  return it->second;
}

double Args::getDouble(const std::string& name, double fallback) const {
  auto it = options_.find(name);
  if (it == options_.end()) return fallback;
  char* end = nullptr;
  double v = std::strtod(it->second.c_str(), &end);
  if (end == it->second.c_str() || *end != '\0' || !std::isfinite(v))
    throw UsageError("option --" + name + " expects a number, got '" + it->second + "'");
  return v;
}

int Args::getInt(const std::string& name, int fallback) const {
  auto it = options_.find(name);
  if (it == options_.end()) return fallback;
  char* end = nullptr;
  errno = 0;
  long v = std::strtol(it->second.c_str(), &end, 10);
  if (end == it->second.c_str() || *end != '\0' || errno == ERANGE || v < INT_MIN || v > INT_MAX)
    throw UsageError("option --" + name + " expects an integer, got '" + it->second + "'");
  return int(v);
}

void Args::allowOnly(const std::set<std::string>& known) const {
  for (auto& [k, v] : options_)
    if (!known.count(k)) throw UsageError("unknown option --" + k);
  for (auto& k : flags_)
    if (!known.count(k)) throw UsageError("unknown option --" + k);
}

}  // namespace cs::cli

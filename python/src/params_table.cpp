// Stereo(..., **overrides): core's parameter table (curvestereo/param_table.hpp) gives
// each Python name, its Params field and type, for setting (with type checks), for
// Stereo.params and for the list in error messages. Names are the fields' own in
// snake_case (duMax -> du_max); the table's aliases (the CLI's spellings: max_fov,
// median) are accepted too, and dashes as underscores, so `**{"du-max": 0.3}` works
// too. `lambda` is a Python keyword: pass lambda_=... or **{"lambda": ...}.
#include <cstdio>
#include <cstdlib>

#include "binding.hpp"
#include "curvestereo/param_table.hpp"

namespace cs::py {

namespace {

std::string typeName(pb::handle v) { return std::string(pb::str(v.get_type().attr("__name__"))); }

// Python bools are ints; a flag where a number belongs is almost surely a mistake.
bool isNumber(pb::handle v) {
  return !pb::isinstance<pb::bool_>(v) && (pb::isinstance<pb::int_>(v) || pb::isinstance<pb::float_>(v) ||
                                           pb::hasattr(v, "__index__") || pb::hasattr(v, "__float__"));
}

// A float field as the shortest decimal that reads back to it (0.2, not 0.200000003):
// what the user wrote, and exact when passed back as an override.
double shortest(float v) {
  char buf[32];
  for (int digits = 6; digits < 10; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, double(v));
    if (std::strtof(buf, nullptr) == v) break;
  }
  return std::strtod(buf, nullptr);
}

void set(const ParamInfo& info, Params& p, pb::handle v, const std::string& key) {
  using Type = ParamInfo::Type;
  switch (info.type) {
    case Type::Int: {
      if (pb::isinstance<pb::bool_>(v) || !pb::hasattr(v, "__index__"))
        throw Error("parameter '" + key + "' expects an integer, got " + typeName(v));
      const long long x = pb::int_(pb::reinterpret_borrow<pb::object>(v)).cast<long long>();
      if (x < -(1LL << 30) || x > (1LL << 30)) throw Error("parameter '" + key + "' is out of range");
      info.setNumber(p, double(x));
      break;
    }
    case Type::Float:
    case Type::Double:
      if (!isNumber(v)) throw Error("parameter '" + key + "' expects a number, got " + typeName(v));
      info.setNumber(p, pb::float_(pb::reinterpret_borrow<pb::object>(v)).cast<double>());
      break;
    case Type::Bool:
      // The CLI's on / off, or a Python bool.
      if (pb::isinstance<pb::str>(v)) {
        const std::string s = v.cast<std::string>();
        if (s != "on" && s != "off")
          throw Error("parameter '" + key + "' expects True/False or on/off, got '" + s + "'");
        info.setFlag(p, s == "on");
      } else if (pb::isinstance<pb::bool_>(v)) {
        info.setFlag(p, v.cast<bool>());
      } else {
        throw Error("parameter '" + key + "' expects True/False, got " + typeName(v));
      }
      break;
    case Type::Enum:
      if (!pb::isinstance<pb::str>(v)) throw Error("parameter '" + key + "' expects a string, got " + typeName(v));
      info.setChoiceNamed(p, v.cast<std::string>());
      break;
  }
}

pb::object get(const ParamInfo& info, const Params& p) {
  using Type = ParamInfo::Type;
  switch (info.type) {
    case Type::Int:
      return pb::int_(p.*info.intField);
    case Type::Float:
      return pb::float_(shortest(p.*info.floatField));
    case Type::Double:
      return pb::float_(p.*info.doubleField);
    case Type::Bool:
      return pb::bool_(info.flag(p));
    case Type::Enum:
      break;
  }
  return pb::str(info.text(p));
}

// A key as written (dashes as underscores, lambda_ for the keyword, or an alias) -> its entry.
const ParamInfo* find(const std::string& key) {
  std::string name = key;
  for (char& c : name)
    if (c == '-') c = '_';
  if (name == "lambda_") name = "lambda";
  for (const ParamInfo& info : paramTable())
    if (name == info.name || (info.alias && name == info.alias)) return &info;
  return nullptr;
}

std::string knownList() {
  std::string s;
  for (const ParamInfo& info : paramTable()) s += (s.empty() ? "" : ", ") + std::string(info.name);
  return s;
}

}  // namespace

std::vector<std::string> paramNames() {
  std::vector<std::string> names;
  for (const ParamInfo& info : paramTable()) names.push_back(info.name);
  return names;
}

Params paramsFrom(const std::string& presetName, const pb::dict& overrides) {
  Params p = preset(presetName);
  // Resolve every key first, so that an unknown or doubled key is reported before any
  // value is looked at.
  std::vector<std::pair<const ParamInfo*, std::pair<std::string, pb::handle>>> chosen;
  for (auto item : overrides) {
    if (!pb::isinstance<pb::str>(item.first)) throw Error("parameter names must be strings");
    const std::string key = item.first.cast<std::string>();
    const ParamInfo* info = find(key);
    if (!info) throw Error("unknown parameter '" + key + "' (known: " + knownList() + ")");
    for (const auto& c : chosen)
      if (c.first == info)
        throw Error("parameter '" + std::string(info->name) + "' given twice ('" + c.second.first + "' and '" + key +
                    "')");
    chosen.push_back({info, {key, item.second}});
  }
  // In table order (data_term before lambda), whatever order the caller wrote them in.
  for (const ParamInfo& info : paramTable())
    for (const auto& c : chosen)
      if (c.first == &info) set(info, p, c.second.second, c.second.first);
  p.validate();
  return p;
}

pb::dict paramsToDict(const Params& p) {
  pb::dict d;
  for (const ParamInfo& info : paramTable()) d[info.name] = get(info, p);
  return d;
}

}  // namespace cs::py

// Stereo(..., **overrides): one table maps each Python name to its Params field, for
// setting (with type checks), for Stereo.params and for the list in error messages.
// Names are the fields' own in snake_case (duMax -> du_max); the CLI's spellings are
// accepted as aliases (--max-fov -> max_fov, --median -> median), and dashes as
// underscores, so `**{"du-max": 0.3}` works too. `lambda` is a Python keyword: pass
// lambda_=... or **{"lambda": ...}.
#include <cstdio>
#include <cstdlib>
#include <functional>

#include "binding.hpp"

namespace cs::py {

namespace {

struct Field {
  const char* name;
  std::function<void(Params&, pb::handle, const std::string&)> set;
  std::function<pb::object(const Params&)> get;
};

std::string typeName(pb::handle v) { return std::string(pb::str(v.get_type().attr("__name__"))); }

// Python bools are ints; a flag where a number belongs is almost surely a mistake.
bool isNumber(pb::handle v) {
  return !pb::isinstance<pb::bool_>(v) && (pb::isinstance<pb::int_>(v) || pb::isinstance<pb::float_>(v) ||
                                           pb::hasattr(v, "__index__") || pb::hasattr(v, "__float__"));
}

Field intField(const char* name, int Params::*member) {
  return {name,
          [member](Params& p, pb::handle v, const std::string& key) {
            if (pb::isinstance<pb::bool_>(v) || !pb::hasattr(v, "__index__"))
              throw Error("parameter '" + key + "' expects an integer, got " + typeName(v));
            const long long x = pb::int_(pb::reinterpret_borrow<pb::object>(v)).cast<long long>();
            if (x < -(1LL << 30) || x > (1LL << 30)) throw Error("parameter '" + key + "' is out of range");
            p.*member = int(x);
          },
          [member](const Params& p) { return pb::object(pb::int_(p.*member)); }};
}

// A float field as the shortest decimal that reads back to it (0.2, not 0.200000003):
// what the user wrote, and exact when passed back as an override.
double shortest(double v) { return v; }
double shortest(float v) {
  char buf[32];
  for (int digits = 6; digits < 10; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, double(v));
    if (std::strtof(buf, nullptr) == v) break;
  }
  return std::strtod(buf, nullptr);
}

template <class T>
Field realField(const char* name, T Params::*member) {
  return {name,
          [member](Params& p, pb::handle v, const std::string& key) {
            if (!isNumber(v)) throw Error("parameter '" + key + "' expects a number, got " + typeName(v));
            p.*member = T(pb::float_(pb::reinterpret_borrow<pb::object>(v)).cast<double>());
          },
          [member](const Params& p) { return pb::object(pb::float_(shortest(p.*member))); }};
}

Field boolField(const char* name, bool Params::*member) {
  return {name,
          [member](Params& p, pb::handle v, const std::string& key) {
            // The CLI's on / off, or a Python bool.
            if (pb::isinstance<pb::str>(v)) {
              const std::string s = v.cast<std::string>();
              if (s != "on" && s != "off")
                throw Error("parameter '" + key + "' expects True/False or on/off, got '" + s + "'");
              p.*member = s == "on";
            } else if (pb::isinstance<pb::bool_>(v)) {
              p.*member = v.cast<bool>();
            } else {
              throw Error("parameter '" + key + "' expects True/False, got " + typeName(v));
            }
          },
          [member](const Params& p) { return pb::object(pb::bool_(p.*member)); }};
}

std::string needString(pb::handle v, const std::string& key) {
  if (!pb::isinstance<pb::str>(v)) throw Error("parameter '" + key + "' expects a string, got " + typeName(v));
  return v.cast<std::string>();
}

// data_term first: choosing the term also sets its lambda, which an explicit lambda then
// overrides (the CLI's order).
const std::vector<Field>& fields() {
  static const std::vector<Field> table = {
      {"data_term",
       [](Params& p, pb::handle v, const std::string& key) { p = p.withDataTerm(parseDataTerm(needString(v, key))); },
       [](const Params& p) { return pb::object(pb::str(dataTermName(p.dataTerm))); }},
      intField("levels", &Params::levels),
      realField("scale", &Params::scale),
      intField("min_width", &Params::minWidth),
      intField("warps", &Params::warps),
      intField("iterations", &Params::iterations),
      realField("du_max", &Params::duMax),
      boolField("median_filter", &Params::medianFilter),
      realField("norm_sigma", &Params::normSigma),
      realField("noise_level", &Params::noiseLevel),
      realField("lambda", &Params::lambda),
      realField("alpha0", &Params::alpha0),
      realField("alpha1", &Params::alpha1),
      realField("beta", &Params::beta),
      realField("eta", &Params::eta),
      realField("w_min", &Params::wMin),
      realField("tensor_sigma", &Params::tensorSigma),
      realField("gamma", &Params::gamma),
      {"init", [](Params& p, pb::handle v, const std::string& key) { p.init = parseInit(needString(v, key)); },
       [](const Params& p) { return pb::object(pb::str(initName(p.init))); }},
      intField("init_level", &Params::initLevel),
      realField("init_max_parallax_deg", &Params::initMaxParallaxDeg),
      realField("init_px_per_plane", &Params::initPxPerPlane),
      intField("init_radius", &Params::initRadius),
      realField("init_p1", &Params::initP1),
      realField("init_p2", &Params::initP2),
      realField("lr_tolerance_px", &Params::lrTolerancePx),
      realField("init_accept", &Params::initAccept),
      realField("occlusion_weight", &Params::occlusionWeight),
      intField("init_warps", &Params::initWarps),
      realField("max_fov_deg", &Params::maxFovDeg),
      realField("epipole_deg", &Params::epipoleDeg),
  };
  return table;
}

// Other spellings -> the table's names.
const std::vector<std::pair<const char*, const char*>>& aliases() {
  static const std::vector<std::pair<const char*, const char*>> table = {
      {"lambda_", "lambda"},
      {"median", "median_filter"},
      {"max_fov", "max_fov_deg"},
      {"epipole", "epipole_deg"},
      {"init_parallax", "init_max_parallax_deg"},
  };
  return table;
}

std::string knownList() {
  std::string s;
  for (const Field& f : fields()) s += (s.empty() ? "" : ", ") + std::string(f.name);
  return s;
}

}  // namespace

std::vector<std::string> paramNames() {
  std::vector<std::string> names;
  for (const Field& f : fields()) names.push_back(f.name);
  return names;
}

Params paramsFrom(const std::string& presetName, const pb::dict& overrides) {
  Params p = preset(presetName);
  // Resolve every key first, so that an unknown or doubled key is reported before any
  // value is looked at.
  std::vector<std::pair<const Field*, std::pair<std::string, pb::handle>>> chosen;
  for (auto item : overrides) {
    if (!pb::isinstance<pb::str>(item.first)) throw Error("parameter names must be strings");
    const std::string key = item.first.cast<std::string>();
    std::string name = key;
    for (char& c : name)
      if (c == '-') c = '_';
    for (const auto& a : aliases())
      if (name == a.first) name = a.second;
    const Field* field = nullptr;
    for (const Field& f : fields())
      if (name == f.name) field = &f;
    if (!field) throw Error("unknown parameter '" + key + "' (known: " + knownList() + ")");
    for (const auto& c : chosen)
      if (c.first == field)
        throw Error("parameter '" + std::string(field->name) + "' given twice ('" + c.second.first + "' and '" + key +
                    "')");
    chosen.push_back({field, {key, item.second}});
  }
  // In table order (data_term before lambda), whatever order the caller wrote them in.
  for (const Field& f : fields())
    for (const auto& c : chosen)
      if (c.first == &f) f.set(p, c.second.second, c.second.first);
  p.validate();
  return p;
}

pb::dict paramsToDict(const Params& p) {
  pb::dict d;
  for (const Field& f : fields()) d[f.name] = f.get(p);
  return d;
}

}  // namespace cs::py

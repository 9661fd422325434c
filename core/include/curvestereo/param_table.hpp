// The solver's parameters (Params) described once: name, type, valid range, one line of
// help. Params::validate(), describe(), the CLI's options and usage, and the Python
// module's overrides all read this table, so a parameter is added in one place.
//
// Names: `name` is snake_case (the Python keyword); the CLI option is its kebab-case
// (--du-max), the C++ field and the validation messages its camelCase (duMax). `alias`
// is a shorter spelling accepted everywhere (the CLI's --max-fov for max_fov_deg).
#pragma once
#include <limits>
#include <string>
#include <vector>

#include "curvestereo/params.hpp"

namespace cs {

struct ParamInfo {
  enum class Type { Int, Float, Double, Bool, Enum };
  // When describe() prints the parameter.
  enum class Shown { Always, Never, Normalised, PlaneSweep };

  const char* name;
  const char* alias = nullptr;
  Type type = Type::Float;
  const char* group = "";  // heading of its block in the CLI's usage
  const char* help = "";

  // Exactly one member pointer, by type; an Enum uses choices / getChoice / setChoice
  // (setting data_term also sets its default lambda: Params::withDataTerm).
  int Params::*intField = nullptr;
  float Params::*floatField = nullptr;
  double Params::*doubleField = nullptr;
  bool Params::*boolField = nullptr;
  std::vector<std::string> choices;  // in the order error messages list them
  const char* noun = "";             // "unknown <noun> 'x' (known: ...)"
  int (*getChoice)(const Params&) = nullptr;
  void (*setChoice)(Params&, int) = nullptr;

  // Valid range of a number (±inf: unbounded on that side; non-finite values are refused).
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
  bool loOpen = false, hiOpen = false;

  Shown shown = Shown::Always;
  const char* describeKey = nullptr;  // describe()'s key when not alias / name

  // "du-max"; the alias's kebab-case when there is one (the CLI's usual spelling).
  std::string cliName() const;
  std::string cliLongName() const;  // kebab-case of name
  std::string cppName() const;      // "duMax"
  std::string key() const;          // describe()'s key

  // The value as a number (Int / Float / Double), as text (every type: "on", "normalised").
  double number(const Params& p) const;
  void setNumber(Params& p, double v) const;
  std::string text(const Params& p) const;
  bool flag(const Params& p) const { return p.*boolField; }
  void setFlag(Params& p, bool v) const { p.*boolField = v; }
  // Enum: the choice by name; throws cs::Error "unknown <noun> 'x' (known: a, b)".
  void setChoiceNamed(Params& p, const std::string& choice) const;

  // "" when the value is valid, else "must be in [1, 12]" (Int / Float / Double).
  std::string rangeError(const Params& p) const;
  // "[1, 12]", "> 0", "" for the usage text.
  std::string rangeText() const;
};

// Every parameter, in the order they are applied (data_term before lambda, so that an
// explicit lambda overrides the data term's default) and described.
const std::vector<ParamInfo>& paramTable();
// The entry of that name (snake_case, or its alias); throws cs::Error for an unknown one.
const ParamInfo& paramInfo(const std::string& name);

}  // namespace cs

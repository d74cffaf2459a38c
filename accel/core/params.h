// Structure parameters given as k=v strings (CLI --param, suite files), checked strictly.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "accel/core/error.h"

namespace ab {

/// A parameter that is unknown, malformed or out of range. The message names the parameter.
struct ParamError : InputError {
  using InputError::InputError;
};

/// k=v parameters. A structure reads each of its fields with get(), which parses the value (or takes
/// the default) and records the effective value; finish() then rejects any key nobody read.
class Params {
 public:
  Params() = default;
  /// From a key -> value map.
  explicit Params(std::map<std::string, std::string> values) : values_(std::move(values)) {}
  /// Parses "k=v" (throws ParamError when there is no '=' or the key is empty); a repeated key is an error.
  void add(const std::string& kv);
  /// Sets a key to a value (replacing any earlier one).
  void set(const std::string& key, const std::string& value) { values_[key] = value; }

  /// Reads an integer in [lo, hi].
  long long get_int(const std::string& key, long long def, long long lo, long long hi);
  /// Reads a finite number in [lo, hi].
  double get_float(const std::string& key, double def, double lo, double hi);
  /// Reads one of the allowed words.
  std::string get_choice(const std::string& key, const std::string& def,
                         const std::set<std::string>& allowed);
  /// Reads a boolean (true/false/1/0/yes/no/on/off).
  bool get_bool(const std::string& key, bool def);

  /// Reads a Config field in place: its current value is the default (so a structure's defaults are
  /// written once, in its Config's initializers) and the value read replaces it. Integers and floats are
  /// checked against [lo, hi].
  template <class T>
  requires std::is_arithmetic_v<T> &&
      (!std::is_same_v<T, bool>)void read(const std::string& key, T& field, double lo, double hi) {
    if constexpr (std::is_integral_v<T>) {
      field = T(get_int(key, (long long)field, (long long)lo, (long long)hi));
    } else {
      field = T(get_float(key, shortest_decimal(field), lo, hi));
    }
  }
  /// Reads a boolean Config field in place.
  void read(const std::string& key, bool& field) { field = get_bool(key, field); }
  /// Reads an enumerated Config field in place, spelled by one of `words` (word -> value).
  template <class E>
  void read(const std::string& key, E& field, const std::map<std::string, E>& words) {
    std::string def, value;
    std::set<std::string> allowed;
    for (const auto& [w, e] : words) {
      allowed.insert(w);
      if (e == field) def = w;
    }
    value = get_choice(key, def, allowed);
    field = words.at(value);
  }

  /// Throws ParamError naming the first key that no get() read.
  void finish(const std::string& owner) const;
  /// Effective values of everything read (defaults included).
  const nlohmann::json& effective() const { return effective_; }
  /// The raw map.
  const std::map<std::string, std::string>& values() const { return values_; }
  /// True when no parameter was given.
  bool empty() const { return values_.empty(); }

 private:
  /// The double nearest to the shortest decimal that reads back as x (1.8f records as 1.8, not as
  /// 1.7999999523162842), so float defaults print as they are written.
  static double shortest_decimal(float x);
  static double shortest_decimal(double x) { return x; }
  const std::string* find(const std::string& key);
  std::map<std::string, std::string> values_;
  std::set<std::string> read_;
  nlohmann::json effective_ = nlohmann::json::object();
};

}  // namespace ab

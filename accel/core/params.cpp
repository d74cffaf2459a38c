#include "accel/core/params.h"

#include <charconv>
#include <cmath>
#include <cstdlib>

namespace ab {

void Params::add(const std::string& kv) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos || eq == 0)
    throw ParamError("parameter '" + kv + "' is not of the form key=value");
  const std::string key = kv.substr(0, eq);
  if (values_.count(key)) throw ParamError("parameter '" + key + "' is given twice");
  values_[key] = kv.substr(eq + 1);
}

const std::string* Params::find(const std::string& key) {
  read_.insert(key);
  const auto it = values_.find(key);
  return it == values_.end() ? nullptr : &it->second;
}

long long Params::get_int(const std::string& key, long long def, long long lo, long long hi) {
  long long value = def;
  if (const std::string* s = find(key)) {
    char* end = nullptr;
    errno = 0;
    value = std::strtoll(s->c_str(), &end, 10);
    if (s->empty() || *end != '\0' || errno != 0)
      throw ParamError("parameter '" + key + "': '" + *s + "' is not an integer");
  }
  if (value < lo || value > hi)
    throw ParamError("parameter '" + key + "': " + std::to_string(value) + " is outside [" +
                     std::to_string(lo) + ", " + std::to_string(hi) + "]");
  effective_[key] = value;
  return value;
}

double Params::get_float(const std::string& key, double def, double lo, double hi) {
  double value = def;
  if (const std::string* s = find(key)) {
    char* end = nullptr;
    value = std::strtod(s->c_str(), &end);
    if (s->empty() || *end != '\0' || !std::isfinite(value))
      throw ParamError("parameter '" + key + "': '" + *s + "' is not a finite number");
  }
  if (value < lo || value > hi)
    throw ParamError("parameter '" + key + "': " + std::to_string(value) + " is outside [" +
                     std::to_string(lo) + ", " + std::to_string(hi) + "]");
  effective_[key] = value;
  return value;
}

std::string Params::get_choice(const std::string& key, const std::string& def,
                               const std::set<std::string>& allowed) {
  std::string value = def;
  if (const std::string* s = find(key)) value = *s;
  if (!allowed.count(value)) {
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    throw ParamError("parameter '" + key + "': '" + value + "' is not one of " + list);
  }
  effective_[key] = value;
  return value;
}

bool Params::get_bool(const std::string& key, bool def) {
  bool value = def;
  if (const std::string* s = find(key)) {
    if (*s == "true" || *s == "1" || *s == "yes" || *s == "on")
      value = true;
    else if (*s == "false" || *s == "0" || *s == "no" || *s == "off")
      value = false;
    else
      throw ParamError("parameter '" + key + "': '" + *s + "' is not a boolean");
  }
  effective_[key] = value;
  return value;
}

double Params::shortest_decimal(float x) {
  char buf[32];
  const auto end = std::to_chars(buf, buf + sizeof buf, x).ptr;
  return std::strtod(std::string(buf, end).c_str(), nullptr);
}

void Params::finish(const std::string& owner) const {
  for (const auto& [key, value] : values_)
    if (!read_.count(key)) throw ParamError("unknown parameter '" + key + "' for " + owner);
}

}  // namespace ab

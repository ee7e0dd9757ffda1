#include "core/params.hpp"

#include <cmath>
#include <sstream>

namespace lf {

const Value* ParamTable::lookup(const std::string& name) const {
  asked_.insert(name);
  auto it = values_.find(name);
  return it == values_.end() ? nullptr : &it->second;
}

void ParamTable::fail(const std::string& name, const std::string& what) const {
  throw ParamError(owner_ + ": parameter '" + name + "' " + what);
}

static std::string number_text(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

int64_t ParamTable::get_int(const std::string& name, int64_t fallback, int64_t min, int64_t max) const {
  const Value* v = lookup(name);
  if (!v) return fallback;
  if (!v->is_number()) fail(name, std::string("must be an integer, got a ") + v->type_name());
  double d = v->as_double();
  if (d != std::floor(d)) fail(name, "must be an integer, got " + number_text(d));
  if (d < static_cast<double>(min) || d > static_cast<double>(max))
    fail(name, "must be in [" + std::to_string(min) + ", " + std::to_string(max) + "], got " + number_text(d));
  return static_cast<int64_t>(d);
}

double ParamTable::get_float(const std::string& name, double fallback, double min, double max) const {
  const Value* v = lookup(name);
  if (!v) return fallback;
  if (!v->is_number()) fail(name, std::string("must be a number, got a ") + v->type_name());
  double d = v->as_double();
  if (!std::isfinite(d) || d < min || d > max)
    fail(name, "must be in [" + number_text(min) + ", " + number_text(max) + "], got " + number_text(d));
  return d;
}

bool ParamTable::get_bool(const std::string& name, bool fallback) const {
  const Value* v = lookup(name);
  if (!v) return fallback;
  if (!v->is_bool()) fail(name, std::string("must be true or false, got a ") + v->type_name());
  return v->as_bool();
}

std::string ParamTable::get_string(const std::string& name, const std::string& fallback,
                                   const std::vector<std::string>& allowed) const {
  const Value* v = lookup(name);
  if (!v) return fallback;
  if (!v->is_string()) fail(name, std::string("must be a string, got a ") + v->type_name());
  if (!allowed.empty()) {
    for (const auto& a : allowed)
      if (a == v->as_string()) return a;
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    fail(name, "must be one of " + list + ", got '" + v->as_string() + "'");
  }
  return v->as_string();
}

std::array<double, 3> ParamTable::get_vec3(const std::string& name, std::array<double, 3> fallback) const {
  const Value* v = lookup(name);
  if (!v) return fallback;
  if (!v->is_array() || v->as_array().size() != 3) fail(name, "must be a list of 3 numbers");
  std::array<double, 3> out{};
  for (size_t i = 0; i < 3; ++i) {
    const Value& e = v->as_array()[i];
    if (!e.is_number() || !std::isfinite(e.as_double())) fail(name, "must be a list of 3 numbers");
    out[i] = e.as_double();
  }
  return out;
}

std::vector<double> ParamTable::get_numbers(const std::string& name, std::vector<double> fallback, double min,
                                            double max) const {
  const Value* v = lookup(name);
  if (!v) return fallback;
  if (!v->is_array()) fail(name, "must be a list of numbers");
  std::vector<double> out;
  for (const auto& e : v->as_array()) {
    if (!e.is_number() || !std::isfinite(e.as_double()) || e.as_double() < min || e.as_double() > max)
      fail(name, "must be a list of numbers in [" + number_text(min) + ", " + number_text(max) + "]");
    out.push_back(e.as_double());
  }
  return out;
}

std::vector<std::string> ParamTable::unused() const {
  std::vector<std::string> out;
  for (const auto& [k, v] : values_)
    if (!asked_.count(k)) out.push_back(k);
  return out;
}

void ParamTable::report_unused() const {
  auto names = unused();
  if (names.empty()) return;
  std::string msg = owner_ + ": unknown parameter";
  msg += names.size() > 1 ? "s " : " ";
  for (size_t i = 0; i < names.size(); ++i) msg += (i ? ", '" : "'") + names[i] + "'";
  msg += " (known: ";
  bool first = true;
  for (const auto& k : asked_) {
    msg += (first ? "" : ", ") + k;
    first = false;
  }
  if (first) msg += "none";
  msg += ")";
  throw ParamError(msg);
}

}  // namespace lf

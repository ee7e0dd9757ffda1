#pragma once
// ParamTable: how every component is built (STYLE habit 4). A component reads its parameters by name with a default
// and a valid range; whoever built the table then calls report_unused() so a mistyped name is an error, not a
// silently ignored setting (pbrt's ReportUnused).
#include <array>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/value.hpp"

namespace lf {

class ParamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ParamTable {
 public:
  ParamTable() = default;
  ParamTable(Value::Map values, std::string owner) : values_(std::move(values)), owner_(std::move(owner)) {}

  int64_t get_int(const std::string& name, int64_t fallback, int64_t min, int64_t max) const;
  double get_float(const std::string& name, double fallback, double min, double max) const;
  bool get_bool(const std::string& name, bool fallback) const;
  std::string get_string(const std::string& name, const std::string& fallback,
                         const std::vector<std::string>& allowed = {}) const;
  std::array<double, 3> get_vec3(const std::string& name, std::array<double, 3> fallback) const;
  // A list of finite numbers, each in [min, max].
  std::vector<double> get_numbers(const std::string& name, std::vector<double> fallback, double min, double max) const;
  bool has(const std::string& name) const { return values_.count(name) != 0; }

  // Names present in the table that nobody asked for.
  std::vector<std::string> unused() const;
  // Throws ParamError naming each unknown parameter and the ones this component knows.
  void report_unused() const;

  const Value::Map& values() const { return values_; }
  const std::string& owner() const { return owner_; }

 private:
  const Value* lookup(const std::string& name) const;
  [[noreturn]] void fail(const std::string& name, const std::string& what) const;

  Value::Map values_;
  std::string owner_;
  mutable std::set<std::string> asked_;
};

}  // namespace lf

#pragma once
// Enums that travel as names (operations, phases, error codes): each has one table of {value, name} pairs, and
// these two lookups read it both ways.
#include <optional>
#include <span>
#include <string_view>
#include <utility>

namespace lf {

template <class E>
std::optional<std::string_view> name_in(std::span<const std::pair<E, std::string_view>> table, E value) {
  for (const auto& [v, name] : table)
    if (v == value) return name;
  return std::nullopt;
}

template <class E>
std::optional<E> value_in(std::span<const std::pair<E, std::string_view>> table, std::string_view name) {
  for (const auto& [v, n] : table)
    if (n == name) return v;
  return std::nullopt;
}

}  // namespace lf

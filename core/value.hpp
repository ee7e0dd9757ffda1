#pragma once
// Value: the dynamic tree that scripts produce and control messages carry (parameters, configuration, stats).
// Bulk float data travels as Bytes so that transport can send it as one msgpack `bin`.
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace lf {

struct Bytes {
  std::string data;
  bool operator==(const Bytes&) const = default;
};

class Value {
 public:
  using Array = std::vector<Value>;
  using Map = std::map<std::string, Value, std::less<>>;

  Value() = default;
  Value(std::nullptr_t) {}
  Value(bool b) : data_(b) {}
  Value(int i) : data_(int64_t{i}) {}
  Value(int64_t i) : data_(i) {}
  Value(uint64_t i) : data_(static_cast<int64_t>(i)) {}
  Value(unsigned i) : data_(int64_t{i}) {}
  Value(double d) : data_(d) {}
  Value(const char* s) : data_(std::string(s)) {}
  Value(std::string s) : data_(std::move(s)) {}
  Value(Bytes b) : data_(std::move(b)) {}
  Value(Array a) : data_(std::move(a)) {}
  Value(Map m) : data_(std::move(m)) {}

  bool is_nil() const { return data_.index() == 0; }
  bool is_bool() const { return std::holds_alternative<bool>(data_); }
  bool is_int() const { return std::holds_alternative<int64_t>(data_); }
  bool is_double() const { return std::holds_alternative<double>(data_); }
  bool is_number() const { return is_int() || is_double(); }
  bool is_string() const { return std::holds_alternative<std::string>(data_); }
  bool is_bytes() const { return std::holds_alternative<Bytes>(data_); }
  bool is_array() const { return std::holds_alternative<Array>(data_); }
  bool is_map() const { return std::holds_alternative<Map>(data_); }

  bool as_bool() const { return std::get<bool>(data_); }
  int64_t as_int() const { return is_int() ? std::get<int64_t>(data_) : static_cast<int64_t>(std::get<double>(data_)); }
  double as_double() const { return is_int() ? static_cast<double>(std::get<int64_t>(data_)) : std::get<double>(data_); }
  const std::string& as_string() const { return std::get<std::string>(data_); }
  const Bytes& as_bytes() const { return std::get<Bytes>(data_); }
  Bytes& as_bytes() { return std::get<Bytes>(data_); }
  const Array& as_array() const { return std::get<Array>(data_); }
  Array& as_array() { return std::get<Array>(data_); }
  const Map& as_map() const { return std::get<Map>(data_); }
  Map& as_map() { return std::get<Map>(data_); }

  // Map lookup; nullptr when this is not a map or the key is absent.
  const Value* find(std::string_view key) const;
  // The same, to take from (a received body's bulk bytes are moved out, not copied).
  Value* find(std::string_view key) { return const_cast<Value*>(std::as_const(*this).find(key)); }
  // Human name of the held type, for error messages ("number", "string", ...).
  const char* type_name() const;

  bool operator==(const Value&) const = default;

  using Storage = std::variant<std::monostate, bool, int64_t, double, std::string, Bytes, Array, Map>;
  const Storage& storage() const { return data_; }

 private:
  Storage data_;
};

// A map built by moving its values in: map_of("n", 3, "p", std::move(bytes)). A braced Value::Map{{k, v}, ...}
// copies every value (an initializer list's elements are const), which for bulk Bytes is one more copy of each
// array in every message.
inline void put_all(Value::Map&) {}
template <class V, class... Rest>
void put_all(Value::Map& m, std::string key, V&& value, Rest&&... rest) {
  m.insert_or_assign(std::move(key), Value(std::forward<V>(value)));
  put_all(m, std::forward<Rest>(rest)...);
}
template <class... KeysAndValues>
Value map_of(KeysAndValues&&... kv) {
  Value::Map m;
  put_all(m, std::forward<KeysAndValues>(kv)...);
  return Value(std::move(m));
}

// Floats as little-endian float32 bytes and back (the wire's bulk format, docs/PROTOCOL.md).
Bytes floats_to_bytes(std::span<const float> floats);
// Returns false when the byte count is not a multiple of 4.
bool bytes_to_floats(const Bytes& bytes, std::vector<float>& out);
Bytes u64_to_bytes(std::span<const uint64_t> values);
bool bytes_to_u64(const Bytes& bytes, std::vector<uint64_t>& out);
Bytes u32_to_bytes(std::span<const uint32_t> values);
bool bytes_to_u32(const Bytes& bytes, std::vector<uint32_t>& out);

// Compact JSON (for --stats-json and logs). Bytes are written as their length.
std::string to_json(const Value& value, int indent = 0);

}  // namespace lf

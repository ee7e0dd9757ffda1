#include "core/value.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <sstream>

namespace lf {

static_assert(std::endian::native == std::endian::little,
              "the wire carries little-endian arrays; a big-endian port must byte-swap in value.cpp");

const Value* Value::find(std::string_view key) const {
  if (!is_map()) return nullptr;
  const auto& m = as_map();
  auto it = m.find(key);
  return it == m.end() ? nullptr : &it->second;
}

const char* Value::type_name() const {
  switch (data_.index()) {
    case 0: return "nil";
    case 1: return "boolean";
    case 2: return "integer";
    case 3: return "number";
    case 4: return "string";
    case 5: return "bytes";
    case 6: return "array";
    default: return "table";
  }
}

template <class T>
static Bytes to_bytes(std::span<const T> values) {
  Bytes b;
  b.data.resize(values.size_bytes());
  if (!values.empty()) std::memcpy(b.data.data(), values.data(), values.size_bytes());
  return b;
}

template <class T>
static bool from_bytes(const Bytes& bytes, std::vector<T>& out) {
  if (bytes.data.size() % sizeof(T) != 0) return false;
  out.resize(bytes.data.size() / sizeof(T));
  if (!out.empty()) std::memcpy(out.data(), bytes.data.data(), bytes.data.size());
  return true;
}

Bytes floats_to_bytes(std::span<const float> v) { return to_bytes(v); }
bool bytes_to_floats(const Bytes& b, std::vector<float>& out) { return from_bytes(b, out); }
Bytes u64_to_bytes(std::span<const uint64_t> v) { return to_bytes(v); }
bool bytes_to_u64(const Bytes& b, std::vector<uint64_t>& out) { return from_bytes(b, out); }
Bytes u32_to_bytes(std::span<const uint32_t> v) { return to_bytes(v); }
bool bytes_to_u32(const Bytes& b, std::vector<uint32_t>& out) { return from_bytes(b, out); }

static void json_string(std::ostringstream& os, const std::string& s) {
  os << '"';
  for (unsigned char c : s) {
    switch (c) {
      case '"': os << "\\\""; break;
      case '\\': os << "\\\\"; break;
      case '\n': os << "\\n"; break;
      case '\t': os << "\\t"; break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          os << buf;
        } else {
          os << c;
        }
    }
  }
  os << '"';
}

static void json_value(std::ostringstream& os, const Value& v, int indent, int depth) {
  auto newline = [&](int d) {
    if (indent > 0) os << '\n' << std::string(static_cast<size_t>(d * indent), ' ');
  };
  const auto& s = v.storage();
  switch (s.index()) {
    case 0: os << "null"; break;
    case 1: os << (v.as_bool() ? "true" : "false"); break;
    case 2: os << v.as_int(); break;
    case 3: {
      double d = v.as_double();
      if (std::isfinite(d)) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.9g", d);
        os << buf;
      } else {
        os << "null";
      }
      break;
    }
    case 4: json_string(os, v.as_string()); break;
    case 5: os << v.as_bytes().data.size(); break;
    case 6: {
      os << '[';
      bool first = true;
      for (const auto& e : v.as_array()) {
        if (!first) os << ',';
        first = false;
        newline(depth + 1);
        json_value(os, e, indent, depth + 1);
      }
      if (!v.as_array().empty()) newline(depth);
      os << ']';
      break;
    }
    default: {
      os << '{';
      bool first = true;
      for (const auto& [k, e] : v.as_map()) {
        if (!first) os << ',';
        first = false;
        newline(depth + 1);
        json_string(os, k);
        os << (indent > 0 ? ": " : ":");
        json_value(os, e, indent, depth + 1);
      }
      if (!v.as_map().empty()) newline(depth);
      os << '}';
    }
  }
}

std::string to_json(const Value& value, int indent) {
  std::ostringstream os;
  json_value(os, value, indent, 0);
  return os.str();
}

}  // namespace lf

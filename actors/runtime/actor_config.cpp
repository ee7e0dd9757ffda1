#include "actors/runtime/actor_config.hpp"

namespace lf {

Value ActorConfig::to_value() const {
  Value::Array ins;
  for (const auto& in : inputs) {
    Value::Map entry{{"name", in.name}, {"endpoint", in.endpoint}, {"window", in.window}};
    if (!in.key.empty()) entry["key"] = in.key;
    ins.push_back(std::move(entry));
  }
  Value::Map m{{"params", params},
               {"scene", scene.to_value()},
               {"camera", camera.to_value()},
               {"image", image.to_value()},
               {"inputs", std::move(ins)},
               {"runtime", runtime},
               {"debug", debug},
               {"heartbeat_timeout", heartbeat_timeout},
               {"request_timeout", request_timeout}};
  if (pool) m["pool"] = Value::Map{{"name", pool->name}, {"index", pool->index}, {"count", pool->count}};
  return m;
}

namespace {

// A map field: absent is empty, anything else but a map is an error.
Result<Value::Map> map_field(const Value& body, const char* key) {
  const Value* v = body.find(key);
  if (!v || v->is_nil()) return Value::Map{};
  if (!v->is_map()) return make_error(std::string("CONFIG '") + key + "' must be a map", ErrorCode::bad_request);
  return v->as_map();
}

Result<double> seconds_field(const Value& body, const char* key, double fallback) {
  const Value* v = body.find(key);
  if (!v) return fallback;
  if (!v->is_number() || !(v->as_double() > 0))
    return make_error(std::string("CONFIG '") + key + "' must be a positive number of seconds", ErrorCode::bad_request);
  return v->as_double();
}

}  // namespace

Result<ActorConfig> ActorConfig::from_value(const Value& body) {
  if (!body.is_map()) return make_error("CONFIG body must be a map", ErrorCode::bad_request);
  ActorConfig c;
  auto params = map_field(body, "params");
  auto scene = map_field(body, "scene");
  auto camera = map_field(body, "camera");
  auto image = map_field(body, "image");
  auto runtime = map_field(body, "runtime");
  auto debug = map_field(body, "debug");
  for (const auto* r : {&params, &scene, &camera, &image, &runtime, &debug})
    if (!*r) return r->error();
  c.params = std::move(*params);
  c.scene = SceneSpec::from_value(*scene);
  c.camera = CameraSpec::from_value(*camera);
  c.image = ImageSpec::from_value(*image);
  c.runtime = std::move(*runtime);
  c.debug = std::move(*debug);
  if (const Value* ins = body.find("inputs"); ins && !ins->is_nil()) {
    if (!ins->is_array()) return make_error("CONFIG 'inputs' must be a list", ErrorCode::bad_request);
    for (const auto& in : ins->as_array()) {
      const Value* name = in.find("name");
      const Value* endpoint = in.find("endpoint");
      const Value* window = in.find("window");
      if (!name || !name->is_string() || !endpoint || !endpoint->is_string())
        return make_error("CONFIG names an input without name or endpoint", ErrorCode::bad_request);
      if (window && (!window->is_int() || window->as_int() < 1 || window->as_int() > 1024))
        return make_error("CONFIG input '" + name->as_string() + "': window must be an integer in [1, 1024]",
                          ErrorCode::bad_request);
      const Value* key = in.find("key");
      if (key && (!key->is_string() || key->as_string().size() != 40))
        return make_error("CONFIG input '" + name->as_string() + "': key must be a 40-character Z85 public key",
                          ErrorCode::bad_request);
      c.inputs.push_back({name->as_string(), endpoint->as_string(), window ? window->as_int() : 4,
                          key ? key->as_string() : std::string()});
    }
  }
  if (const Value* pool = body.find("pool"); pool && !pool->is_nil()) {
    const Value* name = pool->find("name");
    const Value* index = pool->find("index");
    const Value* count = pool->find("count");
    if (!name || !name->is_string() || !index || !index->is_int() || !count || !count->is_int() || count->as_int() < 1 ||
        index->as_int() < 0 || index->as_int() >= count->as_int())
      return make_error("CONFIG 'pool' must be {name, index, count} with 0 <= index < count", ErrorCode::bad_request);
    c.pool = PoolPlace{name->as_string(), index->as_int(), count->as_int()};
  }
  auto heartbeat = seconds_field(body, "heartbeat_timeout", c.heartbeat_timeout);
  auto request = seconds_field(body, "request_timeout", c.request_timeout);
  if (!heartbeat) return heartbeat.error();
  if (!request) return request.error();
  c.heartbeat_timeout = *heartbeat;
  c.request_timeout = *request;
  return c;
}

}  // namespace lf

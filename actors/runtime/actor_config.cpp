#include "actors/runtime/actor_config.hpp"

#include "actors/runtime/scheduler.hpp"

namespace lf {

namespace {

Value::Array inputs_value(const std::vector<InputSpec>& inputs) {
  Value::Array ins;
  for (const auto& in : inputs) {
    Value::Map entry{{"name", in.name}, {"window", in.window}};
    if (in.is_pool())
      entry["pool"] = Value::Map{{"strategy", in.strategy}, {"split", in.split}, {"seed", in.seed},
                                 {"subset", in.subset}, {"replicas", inputs_value(in.replicas)}};
    else
      entry["endpoint"] = in.endpoint;
    if (!in.key.empty()) entry["key"] = in.key;
    if (in.lean) entry["lean"] = true;
    if (in.part >= 0) entry["part"] = in.part;
    if (in.answers) entry["answers_at"] = in.answers->letters();
    ins.push_back(std::move(entry));
  }
  return ins;
}

Status read_inputs(const Value& body, const char* field, std::vector<InputSpec>& out, bool pools_allowed = false);

// An input's `answers_at`: letters of L, D, G, S; absent: unknown.
Status read_answers_at(const Value& entry, InputSpec& in) {
  const Value* at = entry.find("answers_at");
  if (!at || at->is_nil()) return Ok{};
  std::optional<AnswerEnds> ends;
  if (at->is_string() && at->as_string().size() <= 8) ends = AnswerEnds::parse(at->as_string());
  if (!ends)
    return make_error("CONFIG input '" + in.name + "': answers_at must be letters of L, D, G and S", ErrorCode::bad_request);
  in.answers = ends;
  return Ok{};
}

// An input's `pool` {strategy, split, seed, replicas: [...]} (a pool this actor dispatches to itself).
Status read_pool(const std::string& name, const Value& pool, InputSpec& in) {
  const Value* strategy = pool.find("strategy");
  const Value* split = pool.find("split");
  const Value* seed = pool.find("seed");
  const Value* subset = pool.find("subset");
  const std::string where = "CONFIG input '" + name + "': pool ";
  if (!strategy || !strategy->is_string() || !Scheduler::parse(strategy->as_string()))
    return make_error(where + "strategy must be round_robin, least_loaded or random", ErrorCode::bad_request);
  if (split && (!split->is_int() || split->as_int() < 0))
    return make_error(where + "split must be a non-negative integer", ErrorCode::bad_request);
  if (seed && (!seed->is_int() || seed->as_int() < 0))
    return make_error(where + "seed must be a non-negative integer", ErrorCode::bad_request);
  if (subset && (!subset->is_int() || subset->as_int() < 0))
    return make_error(where + "subset must be a non-negative integer", ErrorCode::bad_request);
  if (auto st = read_inputs(pool, "replicas", in.replicas); !st) return st;
  if (in.replicas.empty()) return make_error(where + "has no replicas", ErrorCode::bad_request);
  in.strategy = strategy->as_string();
  in.split = split ? split->as_int() : 0;
  in.seed = seed ? seed->as_int() : 0;
  in.subset = subset ? subset->as_int() : 0;
  return Ok{};
}

// A list of {name, endpoint, window?, key?} under `field` ("inputs", "geometry", a pool's "peers" or "replicas");
// absent is empty. Where pools are allowed (CONFIG inputs), an entry may hold `pool` instead of `endpoint`.
Status read_inputs(const Value& body, const char* field, std::vector<InputSpec>& out, bool pools_allowed) {
  const Value* ins = body.find(field);
  if (!ins || ins->is_nil()) return Ok{};
  if (!ins->is_array()) return make_error(std::string("CONFIG '") + field + "' must be a list", ErrorCode::bad_request);
  for (const auto& in : ins->as_array()) {
    const Value* name = in.find("name");
    const Value* endpoint = in.find("endpoint");
    const Value* window = in.find("window");
    const Value* pool = pools_allowed ? in.find("pool") : nullptr;
    if (name && name->is_string() && pool && pool->is_map() && !endpoint) {
      InputSpec spec{name->as_string(), "", 4, ""};
      if (window && (!window->is_int() || window->as_int() < 1 || window->as_int() > 1024))
        return make_error("CONFIG input '" + name->as_string() + "': window must be an integer in [1, 1024]",
                          ErrorCode::bad_request);
      if (window) spec.window = window->as_int();
      if (auto st = read_pool(spec.name, *pool, spec); !st) return st;
      if (auto st = read_answers_at(in, spec); !st) return st;
      out.push_back(std::move(spec));
      continue;
    }
    if (!name || !name->is_string() || !endpoint || !endpoint->is_string())
      return make_error(std::string("CONFIG names ") +
                            (std::string(field) == "inputs"     ? "an input"
                             : std::string(field) == "geometry" ? "a geometry actor"
                             : std::string(field) == "replicas" ? "a pool replica"
                                                                : "a pool peer") +
                            " without name or endpoint",
                        ErrorCode::bad_request);
    if (window && (!window->is_int() || window->as_int() < 1 || window->as_int() > 1024))
      return make_error("CONFIG input '" + name->as_string() + "': window must be an integer in [1, 1024]",
                        ErrorCode::bad_request);
    const Value* key = in.find("key");
    if (key && (!key->is_string() || key->as_string().size() != 40))
      return make_error("CONFIG input '" + name->as_string() + "': key must be a 40-character Z85 public key",
                        ErrorCode::bad_request);
    const Value* lean = in.find("lean");
    if (lean && !lean->is_bool())
      return make_error("CONFIG input '" + name->as_string() + "': lean must be true or false", ErrorCode::bad_request);
    out.push_back({name->as_string(), endpoint->as_string(), window ? window->as_int() : 4,
                   key ? key->as_string() : std::string()});
    out.back().lean = lean && lean->as_bool();
    if (const Value* part = in.find("part"); part && !part->is_nil()) {
      if (!part->is_int() || part->as_int() < 0 || part->as_int() > 65535)
        return make_error("CONFIG input '" + name->as_string() + "': part must be an integer in [0, 65535]",
                          ErrorCode::bad_request);
      out.back().part = part->as_int();
    }
    if (pools_allowed)
      if (auto st = read_answers_at(in, out.back()); !st) return st;
  }
  return Ok{};
}

}  // namespace

Value ActorConfig::to_value() const {
  Value::Array ins = inputs_value(inputs);
  Value::Map m{{"params", params},
               {"scene", scene.to_value()},
               {"camera", camera.to_value()},
               {"image", image.to_value()},
               {"inputs", std::move(ins)},
               {"runtime", runtime},
               {"debug", debug},
               {"heartbeat_timeout", heartbeat_timeout},
               {"request_timeout", request_timeout}};
  if (pool) {
    Value::Map place{{"name", pool->name}, {"index", pool->index}, {"count", pool->count}};
    if (!pool->peers.empty()) place["peers"] = inputs_value(pool->peers);
    m["pool"] = std::move(place);
  }
  if (!geometry.empty()) {
    m["geometry"] = inputs_value(geometry);
    m["part_boxes"] = floats_to_bytes(part_boxes);
  }
  if (!part_triangles.empty()) m["part_triangles"] = u32_to_bytes(part_triangles);
  if (local_part >= 0) m["local_part"] = local_part;
  if (!frame_materials.empty()) m["frame_materials"] = frame_materials;
  if (frame) m["frame"] = static_cast<int64_t>(*frame);
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
  auto read_camera = CameraSpec::from_value(*camera);
  if (!read_camera) return read_camera.error();
  c.camera = *read_camera;
  auto read_image = ImageSpec::from_value(*image);
  if (!read_image) return read_image.error();
  c.image = std::move(*read_image);
  c.runtime = std::move(*runtime);
  c.debug = std::move(*debug);
  if (auto st = read_inputs(body, "inputs", c.inputs, true); !st) return st.error();
  if (auto st = read_inputs(body, "geometry", c.geometry); !st) return st.error();
  if (!c.geometry.empty()) {
    const Value* boxes = body.find("part_boxes");
    if (!boxes || !boxes->is_bytes() || !bytes_to_floats(boxes->as_bytes(), c.part_boxes) ||
        c.part_boxes.size() != 6 * c.geometry.size())
      return make_error("CONFIG 'part_boxes' must hold 6 floats for each of the " + std::to_string(c.geometry.size()) +
                            " parts",
                        ErrorCode::bad_request);
  }
  if (const Value* tris = body.find("part_triangles"); tris && !tris->is_nil()) {
    if (!tris->is_bytes() || !bytes_to_u32(tris->as_bytes(), c.part_triangles))
      return make_error("CONFIG 'part_triangles' must be u32 triangle ids", ErrorCode::bad_request);
  }
  if (const Value* local = body.find("local_part"); local && !local->is_nil()) {
    if (!local->is_int() || local->as_int() < 0 || local->as_int() >= static_cast<int64_t>(c.geometry.size()) ||
        c.part_triangles.empty())
      return make_error("CONFIG 'local_part' must name one of the " + std::to_string(c.geometry.size()) +
                            " parts, with its part_triangles",
                        ErrorCode::bad_request);
    c.local_part = local->as_int();
  }
  if (const Value* changes = body.find("frame_materials"); changes && !changes->is_nil()) {
    if (!is_material_change_list(*changes))
      return make_error("CONFIG 'frame_materials' must be a list of material changes, each a map with a name",
                        ErrorCode::bad_request);
    c.frame_materials = changes->as_array();
  }
  if (const Value* frame = body.find("frame"); frame && !frame->is_nil()) {
    if (!frame->is_int() || frame->as_int() < INT32_MIN || frame->as_int() > INT32_MAX)
      return make_error("CONFIG 'frame' must be a frame number", ErrorCode::bad_request);
    c.frame = static_cast<int>(frame->as_int());
  }
  if (const Value* pool = body.find("pool"); pool && !pool->is_nil()) {
    const Value* name = pool->find("name");
    const Value* index = pool->find("index");
    const Value* count = pool->find("count");
    if (!name || !name->is_string() || !index || !index->is_int() || !count || !count->is_int() || count->as_int() < 1 ||
        index->as_int() < 0 || index->as_int() >= count->as_int())
      return make_error("CONFIG 'pool' must be {name, index, count} with 0 <= index < count", ErrorCode::bad_request);
    c.pool = PoolPlace{name->as_string(), index->as_int(), count->as_int(), {}};
    if (auto st = read_inputs(*pool, "peers", c.pool->peers); !st) return st.error();
    if (!c.pool->peers.empty() && static_cast<int64_t>(c.pool->peers.size()) != c.pool->count - 1)
      return make_error("CONFIG 'pool' has " + std::to_string(c.pool->peers.size()) + " peers for a pool of " +
                            std::to_string(c.pool->count) + " (every other replica, or none)",
                        ErrorCode::bad_request);
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

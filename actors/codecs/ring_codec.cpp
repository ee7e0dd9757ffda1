#include "actors/codecs/ring_codec.hpp"

namespace lf::ring {

using radiosity::SamplePacket;

Value encode_packet(const SamplePacket& p, int home) {
  std::vector<float> points, normals;
  points.reserve(3 * p.points.size());
  normals.reserve(3 * p.points.size());
  for (size_t i = 0; i < p.points.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      points.push_back(p.points[i][c]);
      normals.push_back(p.normals[i][c]);
    }
  return map_of("o", static_cast<int64_t>(p.origin), "s", static_cast<int64_t>(p.serial),
                "it", static_cast<int64_t>(p.iteration), "e", static_cast<int64_t>(p.epoch),
                "r", static_cast<int64_t>(p.route), "home", static_cast<int64_t>(home),
                "p", floats_to_bytes(points), "n", floats_to_bytes(normals), "v", u64_to_bytes(p.visible));
}

namespace {

std::optional<int64_t> integer(const Value& body, const char* key, int64_t lo, int64_t hi) {
  const Value* v = body.find(key);
  if (!v || !v->is_int() || v->as_int() < lo || v->as_int() > hi) return std::nullopt;
  return v->as_int();
}

Error bad(std::string what) { return make_error(std::move(what), ErrorCode::bad_request); }

std::vector<int> ring_list(const Value* v, int rings) {
  std::vector<int> out;
  if (v && v->is_array())
    for (const auto& x : v->as_array())
      if (x.is_int() && x.as_int() >= 0 && x.as_int() < rings) out.push_back(static_cast<int>(x.as_int()));
  return out;
}

std::optional<RGB> rgb(const Value* v) {
  if (!v || !v->is_array() || v->as_array().size() != 3) return std::nullopt;
  const auto& a = v->as_array();
  for (const auto& e : a)
    if (!e.is_number()) return std::nullopt;
  return RGB{static_cast<float>(a[0].as_double()), static_cast<float>(a[1].as_double()),
             static_cast<float>(a[2].as_double())};
}

Value rgb_value(const RGB& c) { return Value::Array{double(c.x), double(c.y), double(c.z)}; }

}  // namespace

Result<PacketMessage> decode_packet(const Value& body, int nodes) {
  auto origin = integer(body, "o", 0, nodes - 1), serial = integer(body, "s", 0, INT64_MAX),
       it = integer(body, "it", 0, INT32_MAX), epoch = integer(body, "e", 0, UINT32_MAX),
       route = integer(body, "r", INT64_MIN, INT64_MAX), home = integer(body, "home", 0, nodes - 1);
  if (!origin || !serial || !it || !epoch || !route || !home)
    return bad("a sample packet needs o, s, it, e, r and home in range");
  const Value *p = body.find("p"), *n = body.find("n"), *v = body.find("v");
  std::vector<float> points, normals;
  PacketMessage out;
  SamplePacket& packet = out.packet;
  if (!p || !n || !v || !p->is_bytes() || !n->is_bytes() || !v->is_bytes() || !bytes_to_floats(p->as_bytes(), points) ||
      !bytes_to_floats(n->as_bytes(), normals) || !bytes_to_u64(v->as_bytes(), packet.visible) ||
      points.size() != 3 * packet.visible.size() || normals.size() != points.size())
    return bad("a sample packet needs p, n (3 floats per sample) and v (one u64 per sample)");
  for (size_t i = 0; i < packet.visible.size(); ++i) {
    packet.points.push_back({points[3 * i], points[3 * i + 1], points[3 * i + 2]});
    packet.normals.push_back({normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]});
  }
  packet.origin = static_cast<uint32_t>(*origin);
  packet.serial = static_cast<uint64_t>(*serial);
  packet.iteration = static_cast<uint32_t>(*it);
  packet.epoch = static_cast<uint32_t>(*epoch);
  packet.route = static_cast<uint64_t>(*route);
  out.home = static_cast<int>(*home);
  return out;
}

Value encode_poll(const PollRequest& poll) {
  Value::Array idle;
  for (int r : poll.idle) idle.push_back(r);
  return Value::Map{{"epoch", static_cast<int64_t>(poll.epoch)}, {"iteration", poll.iteration}, {"idle", std::move(idle)}};
}

Result<PollRequest> decode_poll(const Value& body) {
  auto it = integer(body, "iteration", INT64_MIN, INT64_MAX);
  auto epoch = integer(body, "epoch", 0, UINT32_MAX);
  if (!it || !epoch) return bad("ring.poll needs an epoch and an iteration");
  return PollRequest{static_cast<uint32_t>(*epoch), *it, ring_list(body.find("idle"), INT32_MAX)};
}

Value encode_poll_reply(const PollReply& reply) {
  if (!reply.lent.empty()) {
    Value::Array packets;
    for (const auto& p : reply.lent) packets.push_back(encode_packet(p, static_cast<int>(p.origin)));
    return Value::Map{{"packets", std::move(packets)}};
  }
  Value::Array rings;
  for (int r : reply.idle) rings.push_back(r);
  return Value::Map{{"finished", reply.finished}, {"idle", std::move(rings)}};
}

Result<PollReply> decode_poll_reply(const Value& body, int nodes, int rings) {
  PollReply reply;
  if (const Value* lent = body.find("packets"); lent && lent->is_array()) {
    for (const auto& p : lent->as_array()) {
      auto decoded = decode_packet(p, nodes);
      if (!decoded) return make_error("a lent packet: " + decoded.error().message, ErrorCode::bad_request);
      reply.lent.push_back(std::move(decoded->packet));
    }
  }
  reply.idle = ring_list(body.find("idle"), rings);
  const Value* done = body.find("finished");
  reply.finished = done && done->is_bool() && done->as_bool();
  return reply;
}

Value encode_shooter_report(const ShooterReport& r) {
  Value::Map body{{"epoch", static_cast<int64_t>(r.epoch)},
                  {"iteration", r.iteration},
                  {"unshot_power", r.unshot_power},
                  {"emitted_power", r.emitted_power},
                  {"power_arrived", r.power_arrived}};
  if (r.candidate)
    body["candidate"] = Value::Map{{"patch", static_cast<int64_t>(r.candidate->patch)},
                                   {"power", r.candidate->power},
                                   {"unshot", rgb_value(r.candidate->unshot)}};
  if (r.checkpoint) body["checkpoint"] = encode_elements(*r.checkpoint);
  return body;
}

Result<ShooterReport> decode_shooter_report(const Value& body, size_t patches) {
  ShooterReport r;
  auto it = integer(body, "iteration", -1, INT32_MAX);
  auto epoch = integer(body, "epoch", 0, UINT32_MAX);
  if (!it || !epoch) return bad("ring.shooter needs an epoch and an iteration");
  r.iteration = *it;
  r.epoch = static_cast<uint32_t>(*epoch);
  if (const Value* c = body.find("checkpoint"); c && !c->is_nil()) {
    auto elements = decode_elements(*c, patches);
    if (!elements) return bad("a checkpoint: " + elements.error().message);
    r.checkpoint = std::move(*elements);
  }
  auto number = [&](const char* key) {
    const Value* v = body.find(key);
    return v && v->is_number() ? v->as_double() : 0.0;
  };
  r.unshot_power = number("unshot_power");
  r.emitted_power = number("emitted_power");
  r.power_arrived = number("power_arrived");
  if (const Value* c = body.find("candidate"); c && !c->is_nil()) {
    auto patch = c->is_map() ? integer(*c, "patch", 0, UINT32_MAX - 1) : std::nullopt;
    const Value* power = c->find("power");
    auto unshot = rgb(c->find("unshot"));
    if (!patch || !power || !power->is_number() || !unshot) return bad("a malformed candidate");
    r.candidate = radiosity::Candidate{static_cast<uint32_t>(*patch), power->as_double(), *unshot};
  }
  return r;
}

Value encode_shooter_choice(const std::optional<ShooterChoice>& choice) {
  if (!choice) return Value::Map{{"done", true}};
  return Value::Map{{"shooter", Value::Map{{"iteration", choice->iteration},
                                           {"patch", static_cast<int64_t>(choice->patch)},
                                           {"unshot", rgb_value(choice->unshot)}}}};
}

Result<std::optional<ShooterChoice>> decode_shooter_choice(const Value& body, size_t patches) {
  const Value* shooter = body.find("shooter");
  if (!shooter) return std::optional<ShooterChoice>{};
  auto patch = integer(*shooter, "patch", 0, static_cast<int64_t>(patches) - 1);
  auto it = integer(*shooter, "iteration", 0, INT32_MAX);
  auto unshot = rgb(shooter->find("unshot"));
  if (!patch || !it || !unshot) return bad("the director sent a malformed shooter");
  return std::optional<ShooterChoice>{ShooterChoice{*it, static_cast<uint32_t>(*patch), *unshot}};
}

Value encode_elements(const std::vector<radiosity::Element>& elements) {
  std::vector<uint32_t> patch, corners, depth;
  std::vector<float> points, radiosity, unshot;
  for (const auto& e : elements) {
    if (!e.leaf) continue;
    patch.push_back(e.patch);
    corners.push_back(static_cast<uint32_t>(e.polygon.count));
    depth.push_back(static_cast<uint32_t>(e.depth));
    for (const Vec3& v : e.polygon.v)
      for (int c = 0; c < 3; ++c) points.push_back(v[c]);
    for (int c = 0; c < 3; ++c) {
      radiosity.push_back(e.radiosity[c]);
      unshot.push_back(e.unshot[c]);
    }
  }
  return map_of("patch", u32_to_bytes(patch), "corners", u32_to_bytes(corners), "points", floats_to_bytes(points),
                "radiosity", floats_to_bytes(radiosity), "unshot", floats_to_bytes(unshot), "depth", u32_to_bytes(depth));
}

Result<std::vector<radiosity::Element>> decode_elements(const Value& body, size_t patches) {
  std::vector<uint32_t> patch, corners, depth;
  std::vector<float> points, radiosity, unshot;
  const Value *p = body.find("patch"), *c = body.find("corners"), *x = body.find("points"), *b = body.find("radiosity"),
              *u = body.find("unshot"), *d = body.find("depth");
  if (!p || !c || !x || !b || !u || !d || !p->is_bytes() || !c->is_bytes() || !x->is_bytes() || !b->is_bytes() ||
      !u->is_bytes() || !d->is_bytes() || !bytes_to_u32(p->as_bytes(), patch) || !bytes_to_u32(c->as_bytes(), corners) ||
      !bytes_to_u32(d->as_bytes(), depth) || !bytes_to_floats(x->as_bytes(), points) ||
      !bytes_to_floats(b->as_bytes(), radiosity) || !bytes_to_floats(u->as_bytes(), unshot) ||
      corners.size() != patch.size() || depth.size() != patch.size() || points.size() != 12 * patch.size() ||
      radiosity.size() != 3 * patch.size() || unshot.size() != radiosity.size())
    return bad("malformed elements");
  std::vector<radiosity::Element> elements;
  elements.reserve(patch.size());
  for (size_t i = 0; i < patch.size(); ++i) {
    if (patch[i] >= patches || (corners[i] != 3 && corners[i] != 4) || depth[i] > kMaxElementDepth)
      return bad("an element of an unknown patch");
    radiosity::Element e;
    e.patch = patch[i];
    e.depth = static_cast<int>(depth[i]);
    e.polygon.count = static_cast<int>(corners[i]);
    for (size_t k = 0; k < 4; ++k)
      e.polygon.v[k] = {points[12 * i + 3 * k], points[12 * i + 3 * k + 1], points[12 * i + 3 * k + 2]};
    e.radiosity = {radiosity[3 * i], radiosity[3 * i + 1], radiosity[3 * i + 2]};
    e.unshot = {unshot[3 * i], unshot[3 * i + 1], unshot[3 * i + 2]};
    elements.push_back(e);
  }
  return elements;
}

Value encode_result(const std::vector<radiosity::Element>& elements, uint32_t epoch) {
  Value body = encode_elements(elements);
  body.as_map()["epoch"] = static_cast<int64_t>(epoch);
  return body;
}

Result<ResultMessage> decode_result(const Value& body, size_t patches) {
  auto epoch = integer(body, "epoch", 0, UINT32_MAX);
  if (!epoch) return bad("ring.result needs an epoch");
  auto elements = decode_elements(body, patches);
  if (!elements) return bad("a malformed result");
  return ResultMessage{static_cast<uint32_t>(*epoch), std::move(*elements)};
}

Value encode_rollback(const radiosity::Rollback& r) {
  Value body = encode_elements(r.elements);
  body.as_map()["epoch"] = static_cast<int64_t>(r.epoch);
  body.as_map()["iteration"] = r.iteration;
  return body;
}

Result<radiosity::Rollback> decode_rollback(const Value& body, size_t patches) {
  auto epoch = integer(body, "epoch", 1, UINT32_MAX);
  auto it = integer(body, "iteration", -1, INT32_MAX);
  if (!epoch || !it) return bad("a rollback needs an epoch (from 1) and an iteration");
  auto elements = decode_elements(body, patches);
  if (!elements) return bad("a rollback: " + elements.error().message);
  return radiosity::Rollback{static_cast<uint32_t>(*epoch), *it, std::move(*elements)};
}

}  // namespace lf::ring

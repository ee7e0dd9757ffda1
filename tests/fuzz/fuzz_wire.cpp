// libFuzzer target: everything a peer can put on the wire. The input is split into a header frame and a body frame
// (the first byte says where); the message decoder checks both, and a body that decodes is handed to every body
// decoder an actor or the director applies to bytes from outside: shade requests and replies, HELLO, CONFIG and
// the radiosity ring's messages. A decoder may refuse; it must never crash, read out of bounds or leak.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "actors/codecs/ring_codec.hpp"
#include "actors/codecs/shade_codec.hpp"
#include "actors/runtime/lean_points.hpp"
#include "actors/runtime/actor_config.hpp"
#include "actors/runtime/hello.hpp"
#include "transport/message.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string_view all(reinterpret_cast<const char*>(data) + 1, size - 1);
  const size_t split = std::min<size_t>(data[0], all.size());
  (void)lf::wire::decode(all.substr(0, split), all.substr(split));
  auto body = lf::wire::decode_body(all);
  if (!body) return 0;
  const lf::Value& v = *body;
  (void)lf::decode_shade_request(v);
  (void)lf::read_shade_request(v, 8, 64);
  // A lean request (no nrm or m; o and t for p, tile and s for k) is completed from the scene's triangles and the
  // image: hostile triangle ids, tiles and sample indices must be refused.
  static const lf::Scene cornell = std::move(lf::Scene::builtin("cornell").value());
  static const lf::PixelKeys keys{64, lf::SamplerKind::sobol};
  (void)lf::read_shade_request(v, cornell.materials().size(), cornell.triangle_count(), &cornell, &keys);
  (void)lf::slice_shade_request(v, 1, 3);
  if (auto fold = lf::decode_pixel_fold(v); fold && *fold) (void)(*fold)->runs();
  (void)lf::decode_radiance(v, 4);
  (void)lf::ActorConfig::from_value(v);
  (void)lf::Hello::check(v, "direct", "direct");
  (void)lf::ring::decode_packet(v, 4);
  (void)lf::ring::decode_poll(v);
  (void)lf::ring::decode_poll_reply(v, 4, 2);
  (void)lf::ring::decode_shooter_report(v, 16);
  (void)lf::ring::decode_shooter_choice(v, 16);
  (void)lf::ring::decode_result(v, 16);
  (void)lf::ring::decode_rollback(v, 16);
  return 0;
}

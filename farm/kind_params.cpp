#include "farm/kind_params.hpp"

namespace lf {

RendererParams RendererParams::read(const ParamTable& p) {
  RendererParams r;
  r.batch = p.get_int("batch", r.batch, 1, 1 << 20);
  r.window = p.get_int("window", r.window, 1, 64);
  r.tiles_in_flight = p.get_int("tiles_in_flight", r.tiles_in_flight, 1, 64);
  r.tiles_per_message = p.get_int("tiles_per_message", r.tiles_per_message, 1, 64);
  if (p.get_string("mode", "async", {"async", "sync"}) == "sync")
    r.batch = r.window = r.tiles_in_flight = r.tiles_per_message = 1;
  return r;
}

Value::Map RendererParams::to_map() const {
  return Value::Map{{"batch", batch},
                    {"window", window},
                    {"tiles_in_flight", tiles_in_flight},
                    {"tiles_per_message", tiles_per_message}};
}

MultiplexerParams MultiplexerParams::read(const ParamTable& p) {
  MultiplexerParams m;
  m.strategy = p.get_string("strategy", m.strategy, {"round_robin", "least_loaded", "random"});
  m.split = p.get_int("split", m.split, 0, 1 << 20);
  m.window = p.get_int("window", m.window, 1, 64);
  m.seed = p.get_int("seed", m.seed, 0, INT32_MAX);
  m.subset = p.get_int("subset", m.subset, -1, 1 << 20);
  m.dispatch = p.get_string("dispatch", m.dispatch, {"clients", "process"});
  return m;
}

Value::Map MultiplexerParams::to_map() const {
  return Value::Map{{"strategy", strategy}, {"split", split}, {"window", window}, {"seed", seed}, {"subset", subset},
                    {"dispatch", dispatch}};
}

int64_t input_window(const ActorSpec& asker) {
  if (asker.is_renderer()) return RendererParams::read(ParamTable(asker.params, asker.name)).window;
  if (asker.is_multiplexer()) return MultiplexerParams::read(ParamTable(asker.params, asker.name)).window;
  return 4;
}

}  // namespace lf

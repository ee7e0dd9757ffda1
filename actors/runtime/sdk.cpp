#include "actors/runtime/sdk.hpp"

#include <malloc.h>

#include <cstdio>
#include <string>

#include "actors/runtime/lightop_actor.hpp"
#include "actors/runtime/runtime.hpp"
#include "core/log.hpp"

namespace lf {

int serve_lightop(const LightOpKind& kind, int argc, char** argv) {
  mallopt(M_MMAP_THRESHOLD, 256 << 20);  // see cli/main.cpp
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
  ActorArgs args;
  bool curve = false;
  for (int i = 1; i < argc; i += 2) {
    std::string key = argv[i];
    if (key == "--curve") {
      curve = true;
      --i;
      continue;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "%s: option '%s' needs a value\n", argv[0], key.c_str());
      return 2;
    }
    if (key == "--kind") args.kind = argv[i + 1];
    else if (key == "--name") args.name = argv[i + 1];
    else if (key == "--director") args.director = argv[i + 1];
    else if (key == "--bind") args.bind = argv[i + 1];
    else {
      std::fprintf(stderr, "%s: unknown option '%s'\n", argv[0], key.c_str());
      return 2;
    }
  }
  if (args.kind.empty() || args.name.empty() || args.director.empty()) {
    std::fprintf(stderr, "usage: %s --kind KIND --name NAME --director ENDPOINT [--bind ENDPOINT] [--curve]\n"
                         "(a lightfarm actor serving LightOp '%.*s'; see docs/writing-an-actor.md)\n",
                 argv[0], static_cast<int>(kind.name.size()), kind.name.data());
    return 2;
  }
  set_log_name(args.name);
  if (curve) {
    auto keys = read_farm_keys_from_stdin();
    if (!keys) {
      log_error(keys.error().message);
      return 2;
    }
    args.keys = std::move(*keys);
  }
  install_stop_signals();
  auto actor = make_lightop_actor(kind);
  Runtime runtime(args);
  return runtime.run(*actor);
}

}  // namespace lf

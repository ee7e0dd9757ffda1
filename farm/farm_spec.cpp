#include "farm/farm_spec.hpp"

#include <algorithm>

namespace lf {

int FarmSpec::pool_of(int i) const {
  for (size_t m = 0; m < actors.size(); ++m)
    if (actors[m].is_multiplexer())
      for (int in : actors[m].inputs)
        if (in == i) return static_cast<int>(m);
  return -1;
}

std::vector<int> FarmSpec::pools() const {
  std::vector<int> pool(actors.size(), -1);
  // Searched from the last multiplexer back, so that an actor listed by two gets the first, as pool_of says.
  for (size_t m = actors.size(); m-- > 0;)
    if (actors[m].is_multiplexer())
      for (int in : actors[m].inputs) pool.at(static_cast<size_t>(in)) = static_cast<int>(m);
  return pool;
}

ActorRole ActorSpec::role() const {
  if (runtime.count("cmd")) return ActorRole::plugin;
  const auto k = find_actor_kind(kind);
  return k ? k->role : ActorRole::lightop;  // an unknown kind is refused where it is declared
}

bool ActorSpec::loads_scene() const {
  if (runtime.count("cmd")) return false;
  const auto k = find_actor_kind(kind);
  return !k || k->loads_scene;
}

std::vector<std::string> FarmSpec::renderer_names() const {
  std::vector<std::string> names;
  for (const auto& a : actors)
    if (a.is_renderer()) names.push_back(a.name);
  return names;
}

int FarmSpec::renderer_count() const {
  int n = 0;
  for (const auto& a : actors) n += a.is_renderer();
  return n;
}

int FarmSpec::find(const std::string& name) const {
  for (size_t i = 0; i < actors.size(); ++i)
    if (actors[i].name == name) return static_cast<int>(i);
  return -1;
}

const HostSpec* FarmSpec::host_of(const ActorSpec& actor) const {
  static const HostSpec kLocal;
  for (const auto& h : hosts)
    if (h.name == actor.host) return &h;
  return actor.host == kLocal.name ? &kLocal : nullptr;
}

std::vector<const HostSpec*> FarmSpec::hosts_in_use() const {
  std::vector<const HostSpec*> used;
  for (const auto& a : actors)
    if (const HostSpec* h = host_of(a); h && a.has_process() && std::find(used.begin(), used.end(), h) == used.end())
      used.push_back(h);
  return used;
}

bool FarmSpec::has_remote_hosts() const {
  for (const auto& a : actors)
    if (const HostSpec* h = host_of(a); h && a.has_process() && h->remote()) return true;
  return false;
}

std::vector<std::string> FarmSpec::setting_warnings() const {
  std::vector<std::string> out;
  if (security == "none" && has_remote_hosts())
    out.push_back("farm { security = \"none\" }: the links to other hosts are neither authenticated nor encrypted; "
                  "anyone who can reach them can send the actors work and read what they send (\"curve\" is the "
                  "default)");
  return out;
}

}  // namespace lf

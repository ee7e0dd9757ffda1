#pragma once
// Builders of a FarmSpec: plain functions over the graph, so that what a script means can be tested without Lua.
// The Lua binding (lua/script.cpp) only reads arguments and calls these; each returns an error message without a
// location, which the binding raises at the script line.
#include <string>
#include <vector>

#include "core/result.hpp"
#include "farm/farm_spec.hpp"
#include "farm/kind_params.hpp"
#include "radiosity/config.hpp"

namespace lf {

// `wanted`, or wanted-2, wanted-3, ... : the first name no actor has.
std::string unique_name(const FarmSpec& spec, const std::string& wanted);
// Adds `actor` under the first free name from its own (direct, direct-2, ...); returns its index.
int add_actor(FarmSpec& spec, ActorSpec actor);
// True when actor `i` is the renderers' lighting or some actor's input.
bool is_wired(const FarmSpec& spec, int i);

// Placement lists (host = {h1, h2, ...}) spread actors round robin in declaration order: replica, renderer or ring
// node i goes to hosts[i % n], and a pool's multiplexer or a ring's LightOp to hosts[0].

// A pool: actor `op` (with, for a nested multiplexer, its replicas) becomes replica 0 and `replicas` - 1 copies are
// added; the replicas are renamed NAME.0, NAME.1, ... (inner replicas NAME.1.0, ...), and a multiplexer named `name`
// (usually the op's own: to the network the pool is that op) is added over them. With `hosts`, replica i and its
// subtree go to hosts[i % n]; without, the replicas stay where the op was placed and the multiplexer is local.
struct PoolSpec {
  int op = -1;
  int replicas = 2;
  std::string name;  // empty: the op's name
  MultiplexerParams params;
  std::vector<std::string> hosts;
  SourceLoc loc;
  std::vector<double> slowdown;  // debug: one factor >= 1 per replica, or empty
};
// The most actors a farm may have (every one is a process).
inline constexpr size_t kMaxActors = 4096;

// Returns the multiplexer's index.
Result<int> replicate(FarmSpec& spec, const PoolSpec& pool);

// `count` renderers renderer-0 .. renderer-(count-1), all asking actor `lighting`.
void add_renderers(FarmSpec& spec, int count, int lighting, const RendererParams& params,
                   const std::vector<std::string>& hosts, const SourceLoc& loc);

// A radiosity ring: rings x ring_length `radiosity_node` actors NAME.RING.POSITION, each with every other node as an
// input and `params` plus its own `node` number, then the `radiosity` LightOp named NAME that shades with their
// solution. Returns the LightOp's index.
// partition { parts = N }: N `geometry` actors, "geometry.0" ... (spread over `hosts` as renderers are), each holding
// one part of the scene (render/tracing/partition.hpp).
Status add_partition(FarmSpec& spec, int parts, bool colocate, const std::vector<std::string>& hosts,
                     const SourceLoc& loc);

Result<int> expand_ring(FarmSpec& spec, const radiosity::RingConfig& config, const Value::Map& params,
                        const std::string& name, const std::vector<std::string>& hosts, const SourceLoc& loc);

// Marks each pool whose clients can dispatch to its replicas themselves (ActorSpec::dispatched_by_clients): its
// dispatch is "clients", its replicas are not pools, and every client runs the farm's runtime (renderers and
// built-in LightOps; not exec plug-ins, which get the multiplexer process). Call once the graph is complete.
void settle_pool_dispatch(FarmSpec& spec);

// The checks a finished graph must pass: renderers and their lighting exist, names are unique, inputs are in
// range and form no cycle, every host is declared, and every LightOp is reachable from the renderers' lighting
// (a dangling one would run for nothing). Errors name the actor's script line.
Status validate(const FarmSpec& spec);

// In a partitioned farm, whether actor `a` sends rays to the geometry actors: renderers (their camera rays) and the
// LightOps whose kind traces through the parts (direct, pathtrace), not pools.
bool traces_through_parts(const ActorSpec& a);
// partition { colocate = true }: the part actor `i` holds itself, or -1. Replica j of a pool whose op traces through
// the parts holds part j mod N.
int64_t colocated_part(const FarmSpec& spec, int i);

// The actor graph as Graphviz DOT: one node per actor (renderers folded into one), edges in the direction light
// flows, one cluster per host; a radiosity ring drawn as rings.
std::string to_dot(const FarmSpec& spec);

}  // namespace lf

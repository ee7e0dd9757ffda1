#pragma once
// Which replicas of a pool each client connects to. A client that connected to every replica made the farm's
// connections grow as clients x replicas: 192 renderers and 64 replicas on 64 hosts were 12,288 CURVE handshakes
// (about 4 ms of CPU each, both ends, on the test machine), which starved a two-core rig for half a minute. Each
// client now connects to a subset; together the subsets cover every replica evenly, and the replicas left out are
// the client's spares, connected one at a time as its own are lost.
#include <cstdint>
#include <vector>

namespace lf {

// How many of a pool's `replicas` each of its `clients` connects to: `asked` when it is 0 (all) or more; otherwise
// (-1) enough that every replica has a client (replicas / clients, rounded up) and that each of the `window`
// requests a client keeps in flight can be on a replica of its own with as many again to choose from (2 x window);
// never more than there are replicas.
int64_t pool_subset(int64_t asked, int64_t replicas, int64_t clients, int64_t window);

// Client `client`'s order of replicas 0 .. replicas-1: its subset first (`subset` consecutive ones from
// client x subset, wrapping around, so that the clients' subsets deal their connections evenly: each replica gets
// clients x subset / replicas of them, rounded down or up), then the others in order after it. A subset of 0 or of
// every replica gives 0, 1, 2, ...
std::vector<int64_t> pool_order(int64_t replicas, int64_t subset, int64_t client);

// Moves replicas on the client's own host (`near[r]`) that `order` left among the spares to just after its first
// `subset`, at most `subset` of them, and returns how many to connect now. They are reached over IPC, without CURVE
// or TCP, and least_loaded prefers them; the dealt subset stays whole, so every replica keeps its clients.
int64_t add_near_replicas(std::vector<int64_t>& order, int64_t subset, const std::vector<bool>& near);

}  // namespace lf

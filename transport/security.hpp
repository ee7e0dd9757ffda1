#pragma once
// CURVE on every link, so that no stranger on the network can join a farm or read its traffic. The director makes a
// keypair for itself and one for every actor; each actor gets its own secret outside its command line and environment
// (the first line of its standard input), with the public keys of the whole farm. Every server socket (the director's
// control socket, each actor's data socket) speaks CURVE with its own keypair and lets in only clients whose public key
// is the farm's: a ZAP handler in each process checks them and logs refusals, at most one line a second.
#include <atomic>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "core/result.hpp"

#ifdef LIGHTFARM_ALGORITHM_LAYER
#error "render/ and radiosity/ must not include transport headers (algorithm code cannot reach the network)"
#endif

namespace lf::wire {

struct CurveKeys {
  std::string public_key;  // Z85, 40 characters
  std::string secret_key;
};
CurveKeys make_curve_keypair();

// What one actor is given: its keys, the director's public key, and every public key the farm accepts.
struct FarmKeys {
  CurveKeys own;
  std::string director;
  std::vector<std::string> allowed;
  // One line: "LFKEYS1 OWN_PUBLIC OWN_SECRET DIRECTOR_PUBLIC ALLOWED_1 ALLOWED_2 ...".
  std::string to_line() const;
  static Result<FarmKeys> from_line(const std::string& line);
};

class Socket;

// Serves ZAP (ZeroMQ's authentication protocol) for this process while it lives: a CURVE client is let in only if
// its public key is in `allowed`. Watched server sockets also report handshakes that fail before ZAP is asked (a
// client without CURVE at all); every refusal is counted and logged, at most one line a second.
class Authenticator {
 public:
  explicit Authenticator(std::set<std::string> allowed);
  ~Authenticator();
  Authenticator(const Authenticator&) = delete;
  Authenticator& operator=(const Authenticator&) = delete;
  // Call from the socket's thread, before it binds.
  void watch(Socket& server);
  uint64_t refused() const { return refused_; }

 private:
  void serve();
  std::set<std::string> allowed_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> refused_{0};
  std::mutex mutex_;
  std::vector<std::string> monitors_;  // inproc endpoints of socket monitors, for the thread to connect
  std::thread thread_;
};

}  // namespace lf::wire

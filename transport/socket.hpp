#pragma once
// Sockets that speak lightfarm messages. Only transport/ sees ZeroMQ; actors use these.
//
// Router: binds, talks to many peers, each message tagged with the peer's routing id.
// Dealer: connects to one router; its routing id is the actor's name.
// Every received message is validated (frame count, header, body); a bad one arrives as an Error, never a throw.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "transport/message.hpp"

namespace lf::wire {

struct Incoming {
  std::string peer;          // routing id of the sender (Router only)
  Result<Message> message;   // or why the bytes were refused
  size_t bytes = 0;
};

struct SocketCounters {
  uint64_t messages_in = 0, messages_out = 0, bytes_in = 0, bytes_out = 0;
};

class Socket {
 public:
  enum class Kind { router, dealer };
  Socket(Kind kind, const std::string& identity = {});
  ~Socket();
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;

  // Binds and returns the endpoint peers should connect to (a "*"/0 port is resolved to the real one).
  Result<std::string> bind(const std::string& endpoint);
  Status connect(const std::string& endpoint);

  // Dealer: send to the connected router. Router: send to `peer`. False if the peer is gone or the send timed out.
  bool send(const Message& message);
  bool send_to(const std::string& peer, const Message& message);
  // Sends pre-encoded frames (used to forward or to test hostile bytes).
  bool send_raw(std::vector<std::string> frames);

  // Non-blocking; nullopt when nothing is waiting.
  std::optional<Incoming> receive();

  void set_linger_ms(int ms);
  // Connections the kernel queues for accept (before bind); it caps this at net.core.somaxconn.
  void set_backlog(int connections);
  // CURVE, before bind/connect: a server with its secret key (clients are checked by this process's
  // Authenticator), or a client with its keypair and the server's public key. All keys Z85.
  void make_curve_server(const std::string& secret_key);
  void make_curve_client(const std::string& public_key, const std::string& secret_key, const std::string& server_key);
  const SocketCounters& counters() const { return counters_; }
  void* native();  // for Poller

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Kind kind_;
  SocketCounters counters_;
};

// The address of this machine's interface that packets to `host` (a name or IPv4 address) leave from: where that
// host can reach us. Sends nothing.
Result<std::string> local_address_towards(const std::string& host);

// For helper threads (heartbeats, the ZAP handler): signals go to the main thread, whose loop checks its flags;
// here they would only interrupt a poll.
void block_signals_in_this_thread();

// Waits until one of the sockets has input or the timeout passes.
class Poller {
 public:
  void add(Socket& socket);
  void clear() {
    sockets_.clear();
    ready_.clear();
  }
  // Returns, for each added socket in order, whether it is readable. timeout_ms < 0 waits forever.
  // Interrupted by a signal: returns all false.
  const std::vector<bool>& wait(long timeout_ms);

 private:
  std::vector<Socket*> sockets_;
  std::vector<bool> ready_;
};

}  // namespace lf::wire

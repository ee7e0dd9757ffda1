#pragma once
// RequestClient: asynchronous request/reply with one peer. Requests carry ids and are answered later; at most
// `window` are outstanding at once and the rest wait in order. Nothing here blocks on an answer: the owner's
// poll loop calls on_readable() and the matching callback runs.
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <string>

#include "core/log.hpp"
#include "transport/socket.hpp"

namespace lf::wire {

class RequestClient {
 public:
  // The reply, or an Error: an ERROR reply (its code, and its message prefixed with the peer's name), a timeout,
  // or a send that failed.
  using Callback = std::function<void(Result<Message>)>;

  RequestClient(std::string self_name, std::string peer_name, size_t window);

  // CURVE for this link: this client's keypair and the peer's public key (before connect).
  void use_curve(const std::string& public_key, const std::string& secret_key, const std::string& server_key) {
    socket_.make_curve_client(public_key, secret_key, server_key);
  }
  Status connect(const std::string& endpoint);
  void request(Op op, Value body, Callback callback);
  // Reads every waiting reply and runs its callback. Replies whose id is not outstanding (late or duplicated)
  // are dropped and counted.
  void on_readable();
  // Forgets every outstanding and queued request without running callbacks (the peer is gone; whoever owns the
  // work re-sends it elsewhere). Late replies to them are then dropped as strays.
  void abandon_all();
  // Requests unanswered for longer than `seconds` fail with "no answer from PEER within N s" (code timeout; 0: never).
  void set_timeout(double seconds) { timeout_ = seconds; }
  // Fails every request older than the timeout; call it from the poll loop.
  void expire_overdue();
  // The whole farm was paused (Ctrl-Z): time spent stopped is nobody's fault, so outstanding requests wait anew.
  void restart_deadlines();

  size_t outstanding() const { return outstanding_.size(); }
  size_t queued() const { return queue_.size(); }
  uint32_t peer_queue() const { return peer_queue_; }  // as last reported in a reply header
  uint64_t dropped_replies() const { return dropped_; }
  const std::string& peer() const { return peer_name_; }
  Socket& socket() { return socket_; }

 private:
  struct Pending {
    uint64_t id;
    Op op;
    Value body;
    Callback callback;
  };
  void pump();

  std::string self_;
  std::string peer_name_;
  size_t window_;
  Socket socket_;
  uint64_t next_id_ = 1;
  std::deque<Pending> queue_;
  struct Outstanding {
    Callback callback;
    Op op;
    std::chrono::steady_clock::time_point sent;
  };
  std::map<uint64_t, Outstanding> outstanding_;
  double timeout_ = 0;
  uint32_t peer_queue_ = 0;
  uint64_t dropped_ = 0;
  RateLimitedLog bad_messages_;
};

}  // namespace lf::wire

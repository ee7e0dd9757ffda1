#include "transport/socket.hpp"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <pthread.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <zmq.hpp>

#include <algorithm>

namespace lf::wire {

zmq::context_t& zmq_context() {
  static zmq::context_t ctx(1);
  return ctx;
}

namespace {
zmq::context_t& context() { return zmq_context(); }
}  // namespace

struct Socket::Impl {
  zmq::socket_t socket;
  explicit Impl(zmq::socket_type t) : socket(context(), t) {}
};

Socket::Socket(Kind kind, const std::string& identity)
    : impl_(std::make_unique<Impl>(kind == Kind::router ? zmq::socket_type::router : zmq::socket_type::dealer)),
      kind_(kind) {
  auto& s = impl_->socket;
  s.set(zmq::sockopt::linger, 0);
  // Oversized messages are refused by ZeroMQ itself before we buffer them.
  s.set(zmq::sockopt::maxmsgsize, static_cast<int64_t>(kMaxBodyBytes + kMaxHeaderBytes + 1024));
  s.set(zmq::sockopt::sndtimeo, 10000);
  s.set(zmq::sockopt::sndhwm, 100000);
  s.set(zmq::sockopt::rcvhwm, 100000);
  if (!identity.empty()) s.set(zmq::sockopt::routing_id, identity);
  if (kind == Kind::router) s.set(zmq::sockopt::router_mandatory, 1);
}

Socket::~Socket() = default;

void* Socket::native() { return impl_->socket.handle(); }

void Socket::set_linger_ms(int ms) { impl_->socket.set(zmq::sockopt::linger, ms); }
void Socket::set_backlog(int connections) { impl_->socket.set(zmq::sockopt::backlog, connections); }

void Socket::make_curve_server(const std::string& secret_key) {
  auto& s = impl_->socket;
  s.set(zmq::sockopt::curve_server, 1);
  s.set(zmq::sockopt::curve_secretkey, secret_key);
  s.set(zmq::sockopt::zap_domain, "lightfarm");
}

void Socket::make_curve_client(const std::string& public_key, const std::string& secret_key,
                               const std::string& server_key) {
  auto& s = impl_->socket;
  s.set(zmq::sockopt::curve_serverkey, server_key);
  s.set(zmq::sockopt::curve_publickey, public_key);
  s.set(zmq::sockopt::curve_secretkey, secret_key);
}

Result<std::string> Socket::bind(const std::string& endpoint) {
  try {
    impl_->socket.bind(endpoint);
    return impl_->socket.get(zmq::sockopt::last_endpoint);
  } catch (const zmq::error_t& e) {
    return make_error("cannot bind " + endpoint + ": " + e.what());
  }
}

Status Socket::connect(const std::string& endpoint) {
  try {
    impl_->socket.connect(endpoint);
    return Ok{};
  } catch (const zmq::error_t& e) {
    return make_error("cannot connect to " + endpoint + ": " + e.what());
  }
}

namespace {
// Large frames are handed to ZeroMQ without a copy: the string moves to the heap and ZeroMQ frees it once sent.
zmq::message_t to_frame(std::string&& s) {
  if (s.size() < 4096) return zmq::message_t(s.data(), s.size());
  auto* owned = new std::string(std::move(s));
  return zmq::message_t(owned->data(), owned->size(),
                        [](void*, void* hint) { delete static_cast<std::string*>(hint); }, owned);
}
}  // namespace

bool Socket::send_raw(std::vector<std::string> frames) {
  try {
    for (size_t i = 0; i < frames.size(); ++i) {
      auto flags = i + 1 < frames.size() ? zmq::send_flags::sndmore : zmq::send_flags::none;
      const size_t size = frames[i].size();
      zmq::message_t frame = to_frame(std::move(frames[i]));
      // A signal (an actor's SIGCONT after Ctrl-Z/fg, a host agent's SIGCHLD) can interrupt a send before the frame
      // is queued: EINTR, and the frame is still ours. Sent again, not dropped: a dropped middle frame would leave
      // the socket mid-message and weld this message's head onto the next one.
      while (true) {
        try {
          if (!impl_->socket.send(frame, flags)) return false;
          break;
        } catch (const zmq::error_t& e) {
          if (e.num() != EINTR) throw;
        }
      }
      counters_.bytes_out += size;
    }
    ++counters_.messages_out;
    return true;
  } catch (const zmq::error_t&) {
    return false;  // EHOSTUNREACH: the peer is gone
  }
}

bool Socket::send(const Message& m) { return send_raw({encode_header(m.header), encode_body(m.body)}); }

bool Socket::send_to(const std::string& peer, const Message& m) {
  return send_raw({peer, encode_header(m.header), encode_body(m.body)});
}

std::optional<Incoming> Socket::receive() {
  std::vector<zmq::message_t> frames;
  try {
    zmq::message_t first;
    if (!impl_->socket.recv(first, zmq::recv_flags::dontwait)) return std::nullopt;
    frames.push_back(std::move(first));
    // The rest of a message is there once its first frame is (ZeroMQ delivers messages whole). A signal may still
    // interrupt reading it: read on, or its tail would arrive as a message of its own and this one be lost.
    while (frames.back().more()) {
      zmq::message_t part;
      for (int tries = 0;; ++tries) {
        try {
          if (impl_->socket.recv(part, zmq::recv_flags::dontwait)) break;
          if (tries > 1000) return Incoming{{}, make_error("receive failed: a message ended before its last frame"), 0};
        } catch (const zmq::error_t& e) {
          if (e.num() != EINTR) throw;
        }
      }
      frames.push_back(std::move(part));
    }
  } catch (const zmq::error_t& e) {
    if (frames.empty() && (e.num() == EAGAIN || e.num() == EINTR)) return std::nullopt;
    return Incoming{{}, make_error(std::string("receive failed: ") + e.what()), 0};
  }
  size_t bytes = 0;
  for (const auto& f : frames) bytes += f.size();
  counters_.bytes_in += bytes;
  ++counters_.messages_in;

  Incoming in{{}, make_error(""), bytes};
  size_t first = 0;
  if (kind_ == Kind::router) {
    in.peer = frames[0].to_string();
    first = 1;
  }
  const size_t parts = frames.size() - first;
  if (parts != 2) {
    in.message = make_error("expected 2 frames (header, body), got " + std::to_string(parts));
    return in;
  }
  in.message = decode(frames[first].to_string_view(), frames[first + 1].to_string_view());
  return in;
}

void block_signals_in_this_thread() {
  sigset_t set;
  sigemptyset(&set);
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGCONT, SIGTSTP, SIGCHLD}) sigaddset(&set, sig);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

void Poller::add(Socket& s) {
  sockets_.push_back(&s);
  ready_.push_back(false);
}

const std::vector<bool>& Poller::wait(long timeout_ms) {
  std::vector<zmq::pollitem_t> items;
  items.reserve(sockets_.size());
  for (auto* s : sockets_) items.push_back({s->native(), 0, ZMQ_POLLIN, 0});
  std::fill(ready_.begin(), ready_.end(), false);
  try {
    zmq::poll(items.data(), items.size(), std::chrono::milliseconds(timeout_ms));
  } catch (const zmq::error_t&) {
    return ready_;  // EINTR: a signal arrived; the caller checks its flags
  }
  for (size_t i = 0; i < items.size(); ++i) ready_[i] = (items[i].revents & ZMQ_POLLIN) != 0;
  return ready_;
}

Result<std::string> local_address_towards(const std::string& host) {
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* found = nullptr;
  if (int rc = ::getaddrinfo(host.c_str(), "9", &hints, &found); rc != 0 || !found)
    return make_error("cannot resolve '" + host + "': " + ::gai_strerror(rc));
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  std::string out;
  std::string why;
  if (fd < 0) {
    why = std::strerror(errno);
  } else if (::connect(fd, found->ai_addr, found->ai_addrlen) != 0) {  // a UDP connect only picks the route
    why = std::strerror(errno);
  } else {
    sockaddr_in local{};
    socklen_t len = sizeof local;
    char text[INET_ADDRSTRLEN] = {};
    if (::getsockname(fd, reinterpret_cast<sockaddr*>(&local), &len) == 0 &&
        ::inet_ntop(AF_INET, &local.sin_addr, text, sizeof text))
      out = text;
    else
      why = std::strerror(errno);
  }
  if (fd >= 0) ::close(fd);
  ::freeaddrinfo(found);
  if (out.empty()) return make_error("no route to '" + host + "': " + why);
  return out;
}

}  // namespace lf::wire

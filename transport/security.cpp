#include "transport/security.hpp"

#include <zmq.hpp>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "core/log.hpp"
#include "transport/socket.hpp"

namespace lf::wire {

zmq::context_t& zmq_context();  // socket.cpp: every socket of the process, the ZAP handler's too

CurveKeys make_curve_keypair() {
  char pub[41] = {}, sec[41] = {};
  if (zmq_curve_keypair(pub, sec) != 0) return {};
  return {pub, sec};
}

std::string FarmKeys::to_line() const {
  std::string line = "LFKEYS1 " + own.public_key + " " + own.secret_key + " " + director;
  for (const auto& k : allowed) line += " " + k;
  return line;
}

Result<FarmKeys> FarmKeys::from_line(const std::string& line) {
  std::istringstream in(line);
  std::string magic;
  FarmKeys k;
  in >> magic >> k.own.public_key >> k.own.secret_key >> k.director;
  if (magic != "LFKEYS1") return make_error("the keys on standard input do not start with LFKEYS1");
  for (std::string key; in >> key;) k.allowed.push_back(key);
  auto z85 = [](const std::string& s) { return s.size() == 40; };
  if (!z85(k.own.public_key) || !z85(k.own.secret_key) || !z85(k.director) || k.allowed.empty())
    return make_error("the keys on standard input are incomplete (each key is 40 Z85 characters)");
  for (const auto& a : k.allowed)
    if (!z85(a)) return make_error("the keys on standard input are incomplete (each key is 40 Z85 characters)");
  return k;
}

Authenticator::Authenticator(std::set<std::string> allowed) : allowed_(std::move(allowed)) {
  thread_ = std::thread([this] { serve(); });
}

Authenticator::~Authenticator() {
  stop_ = true;
  thread_.join();
}

void Authenticator::watch(Socket& server) {
  static std::atomic<int> next{0};
  const std::string endpoint = "inproc://lightfarm-monitor-" + std::to_string(next++);
  zmq_socket_monitor(server.native(), endpoint.c_str(),
                     ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL | ZMQ_EVENT_HANDSHAKE_FAILED_PROTOCOL);
  std::lock_guard<std::mutex> lock(mutex_);
  monitors_.push_back(endpoint);
}

void Authenticator::serve() {
  block_signals_in_this_thread();
  zmq::socket_t zap(zmq_context(), zmq::socket_type::rep);
  zap.set(zmq::sockopt::linger, 0);
  zap.bind("inproc://zeromq.zap.01");
  std::vector<zmq::socket_t> monitors;
  using Clock = std::chrono::steady_clock;
  auto first_unlogged = Clock::now();
  uint64_t unlogged = 0;
  std::string last_address;
  while (!stop_) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (const auto& endpoint : monitors_) {
        monitors.emplace_back(zmq_context(), zmq::socket_type::pair);
        monitors.back().set(zmq::sockopt::linger, 0);
        monitors.back().connect(endpoint);
      }
      monitors_.clear();
    }
    std::vector<zmq::pollitem_t> items{{zap.handle(), 0, ZMQ_POLLIN, 0}};
    for (auto& m : monitors) items.push_back({m.handle(), 0, ZMQ_POLLIN, 0});
    try {
      zmq::poll(items.data(), items.size(), std::chrono::milliseconds(100));
    } catch (const zmq::error_t&) {
      continue;  // EINTR; the loop checks stop_
    }
    for (size_t i = 1; i < items.size(); ++i) {
      if (!(items[i].revents & ZMQ_POLLIN)) continue;
      // A monitor event: 6 bytes (event, value), then the socket's endpoint.
      zmq::message_t event, where;
      if (!monitors[i - 1].recv(event, zmq::recv_flags::dontwait)) continue;
      if (event.more()) (void)monitors[i - 1].recv(where, zmq::recv_flags::dontwait);
      uint16_t id = 0;
      uint32_t value = 0;
      if (event.size() >= 6) {
        std::memcpy(&id, event.data(), 2);
        std::memcpy(&value, static_cast<const char*>(event.data()) + 2, 4);
      }
      ++refused_;
      if (unlogged++ == 0) first_unlogged = Clock::now();
      // The monitor names the endpoint the connection came in on, not its sender (ZeroMQ does not know it before
      // the handshake); a client that is refused reconnects on its own, so one stranger is counted each time. A
      // handshake left unfinished is a client without CURVE, or one that timed out or gave up half way (a farm's own
      // peers do on an overloaded machine): ZeroMQ does not tell which, so neither does the message.
      char code[16];
      std::snprintf(code, sizeof code, "0x%08x", value);
      last_address = "a connection to " + where.to_string() +
                     (id == ZMQ_EVENT_HANDSHAKE_FAILED_NO_DETAIL
                          ? " that left the handshake unfinished (no CURVE, or it timed out or closed half way)"
                      : value == ZMQ_PROTOCOL_ERROR_ZMTP_MECHANISM_MISMATCH
                          ? " that spoke without CURVE"
                          : " that broke the handshake (ZeroMQ protocol error " + std::string(code) + ")") +
                     ", sender unknown";
    }
    if (items[0].revents & ZMQ_POLLIN) {
      // ZAP request: version, request id, domain, address, identity, mechanism, credentials...
      std::vector<zmq::message_t> frames;
      while (true) {
        zmq::message_t f;
        if (!zap.recv(f, zmq::recv_flags::dontwait)) break;
        const bool more = f.more();
        frames.push_back(std::move(f));
        if (!more) break;
      }
      if (frames.size() < 6) continue;
      const std::string mechanism = frames[5].to_string();
      bool ok = false;
      if (mechanism == "CURVE" && frames.size() >= 7 && frames[6].size() == 32) {
        char z85[41] = {};
        zmq_z85_encode(z85, static_cast<const uint8_t*>(frames[6].data()), 32);
        ok = allowed_.count(z85) > 0;
      }
      const std::string status = ok ? "200" : "400";
      const std::string text = ok ? "OK" : "not a key of this farm";
      zap.send(frames[0], zmq::send_flags::sndmore);
      zap.send(frames[1], zmq::send_flags::sndmore);
      zap.send(zmq::buffer(status), zmq::send_flags::sndmore);
      zap.send(zmq::buffer(text), zmq::send_flags::sndmore);
      zap.send(zmq::buffer(std::string()), zmq::send_flags::sndmore);
      zap.send(zmq::buffer(std::string()), zmq::send_flags::none);
      if (!ok) {
        ++refused_;
        if (unlogged++ == 0) first_unlogged = Clock::now();
        last_address = "from " + frames[3].to_string() + " with an unknown key";
      }
    }
    // Refusals are logged a second after the first one not yet logged, with how many came in that second: one
    // stranger's first attempt and its reconnects are one line, and a stranger cannot flood the log.
    if (unlogged > 0 && (Clock::now() - first_unlogged >= std::chrono::seconds(1) || stop_)) {
      log_warn("refused " + std::to_string(unlogged) + " connection" + (unlogged > 1 ? "s" : "") +
               " that did not present a key of this farm (latest: " + last_address + ")");
      unlogged = 0;
    }
  }
}

}  // namespace lf::wire

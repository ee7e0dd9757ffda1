#include "transport/client.hpp"

#include <cmath>

#include "core/log.hpp"

namespace lf::wire {

RequestClient::RequestClient(std::string self_name, std::string peer_name, size_t window)
    : self_(std::move(self_name)), peer_name_(std::move(peer_name)), window_(window ? window : 1),
      socket_(Socket::Kind::dealer, self_) {}

Status RequestClient::connect(const std::string& endpoint) { return socket_.connect(endpoint); }

void RequestClient::request(Op op, Value body, Callback callback) {
  queue_.push_back(Pending{next_id_++, op, std::move(body), std::move(callback)});
  pump();
}

void RequestClient::pump() {
  while (!queue_.empty() && outstanding_.size() < window_) {
    Pending p = std::move(queue_.front());
    queue_.pop_front();
    Message m = make_request(self_, p.op, std::move(p.body), p.id);
    if (!socket_.send(m)) {
      p.callback(make_error("could not send '" + std::string(op_name(p.op)) + "' to " + peer_name_, ErrorCode::unreachable));
      continue;
    }
    outstanding_.emplace(p.id, Outstanding{std::move(p.callback), p.op, std::chrono::steady_clock::now()});
  }
}

void RequestClient::abandon_all() {
  outstanding_.clear();
  queue_.clear();
}

void RequestClient::restart_deadlines() {
  const auto now = std::chrono::steady_clock::now();
  for (auto& [id, o] : outstanding_) o.sent = now;
}

void RequestClient::expire_overdue() {
  if (timeout_ <= 0 || outstanding_.empty()) return;
  const auto now = std::chrono::steady_clock::now();
  struct Expired {
    Callback callback;
    Op op;
    uint64_t id;
    double waited;
  };
  std::vector<Expired> expired;
  for (auto it = outstanding_.begin(); it != outstanding_.end();) {
    const double waited = std::chrono::duration<double>(now - it->second.sent).count();
    if (waited > timeout_) {
      expired.push_back({std::move(it->second.callback), it->second.op, it->first, waited});
      it = outstanding_.erase(it);
    } else {
      ++it;
    }
  }
  // Which request, and how long it waited: a live peer that makes no progress must be findable from the message.
  for (auto& e : expired)
    e.callback(make_error("no answer from '" + peer_name_ + "' within " + seconds_text(timeout_) + " (request " +
                              std::to_string(e.id) + ", " + std::string(op_name(e.op)) + ", waited " +
                              seconds_text(std::round(e.waited * 10) / 10) + ")",
                          ErrorCode::timeout));
  pump();
}

void RequestClient::on_readable() {
  while (auto in = socket_.receive()) {
    if (!in->message) {
      bad_messages_.warn("dropped a bad message from " + peer_name_ + ": " + in->message.error().message);
      continue;
    }
    Message& m = *in->message;
    if (m.header.type != MsgType::reply && m.header.type != MsgType::error) {
      log_warn("dropped a " + std::string(type_name(m.header.type)) + " from " + peer_name_ +
               " where a reply was expected");
      continue;
    }
    auto it = outstanding_.find(m.header.id);
    if (it == outstanding_.end()) {
      ++dropped_;
      continue;
    }
    Callback cb = std::move(it->second.callback);
    outstanding_.erase(it);
    peer_queue_ = m.header.queue;
    if (m.header.type == MsgType::error) {
      Error e = error_of(m);
      e.message = peer_name_ + ": " + e.message;
      cb(std::move(e));
    } else {
      cb(std::move(m));
    }
  }
  pump();
}

}  // namespace lf::wire

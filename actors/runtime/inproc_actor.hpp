#pragma once
// For tests: an actor's runtime on a thread over inproc:// sockets, with the test as its director (CZMQ's habit of
// testing several nodes in one process). The test reads what the actor tells its director with next(), answers
// with send(), and talks to its data socket at data_endpoint().
#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "actors/runtime/runtime.hpp"

namespace lf::test {

class InprocActor {
 public:
  InprocActor(const std::string& kind, const std::string& name, std::function<std::unique_ptr<Actor>()> make) : name_(name) {
    static int n = 0;
    const std::string tag = std::to_string(++n);
    const std::string control = *director.bind("inproc://director-" + tag);
    ActorArgs args{kind, name, control, "inproc://" + name + "-" + tag};
    thread_ = std::thread([this, args, make] {
      auto actor = make();
      Runtime rt(args);
      exit_status_ = rt.run(*actor);
    });
  }
  ~InprocActor() {
    if (thread_.joinable()) {
      send(wire::make(wire::MsgType::bye, "director"));
      thread_.join();
    }
  }

  // The next message on `s` within `seconds`; nullopt (and nothing failed) when none came.
  static std::optional<wire::Incoming> poll(wire::Socket& s, double seconds) {
    wire::Poller p;
    p.add(s);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < deadline) {
      if (auto in = s.receive()) return in;
      p.wait(5);
    }
    return std::nullopt;
  }
  // The next message on `s`; a test failure when none comes within `seconds`.
  static wire::Incoming receive(wire::Socket& s, double seconds = 10) {
    if (auto in = poll(s, seconds)) return std::move(*in);
    ADD_FAILURE() << "nothing arrived within " << seconds << " s";
    return wire::Incoming{{}, make_error("timeout"), 0};
  }

  // The next control message of `type` from the actor (heartbeats in between are skipped unless asked for).
  wire::Message next(wire::MsgType type) {
    while (true) {
      auto in = receive(director);
      if (!in.message.ok()) return {};
      // Heartbeats come from the actor's heartbeat thread too (routing id NAME#heartbeat).
      if (in.message->header.type == wire::MsgType::heartbeat && type != wire::MsgType::heartbeat) continue;
      EXPECT_EQ(in.peer, name_);
      EXPECT_EQ(in.message->header.type, type)
          << wire::type_name(in.message->header.type) << " " << to_json(in.message->body);
      if (in.message->header.type == wire::MsgType::hello) data_ = in.message->body.find("endpoint")->as_string();
      return std::move(*in.message);
    }
  }
  void send(wire::Message m) { director.send_to(name_, m); }
  // Waits for the runtime to return; its exit status.
  int join() {
    thread_.join();
    return exit_status_;
  }
  const std::string& data_endpoint() const { return data_; }

  wire::Socket director{wire::Socket::Kind::router};

 private:
  std::string name_;
  std::string data_;
  std::thread thread_;
  int exit_status_ = -1;
};

}  // namespace lf::test

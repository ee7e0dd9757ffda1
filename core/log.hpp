#pragma once
// One line per message on stderr, prefixed with who speaks ("lightfarm" or the actor's name).
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

namespace lf {

void set_log_name(std::string name);
// What a line is about, for readers that sort lines (the monitor colours them): most are plain; the farm's losses
// (an actor gone, its work sent elsewhere) and recoveries (a restart, a rollback) say so where they are logged.
enum class LogKind { plain, loss, recovery };
const char* log_kind_name(LogKind kind);  // "plain", "loss", "recovery"
void log_info(const std::string& message, LogKind kind = LogKind::plain);
void log_warn(const std::string& message, LogKind kind = LogKind::plain);
void log_error(const std::string& message);
// Debug lines appear only when LIGHTFARM_DEBUG is set in the environment.
void log_debug(const std::string& message);
// Also hands every line to `observer` (level: "", "warning: ", "error: " or "debug: "), on the thread that logs
// (the director's monitor keeps the log this way). Set it before other threads log; empty to stop.
using LogObserver = std::function<void(const std::string& level, const std::string& message, LogKind kind)>;
void set_log_observer(LogObserver observer);

// Warnings anyone outside the farm can cause (bad or stranger messages) go through one of these: at most one line
// a second, and the next line says how many like it were held back, so nobody can flood the log.
class RateLimitedLog {
 public:
  using Sink = std::function<void(const std::string&)>;
  explicit RateLimitedLog(Sink sink = [](const std::string& m) { log_warn(m); }) : sink_(std::move(sink)) {}
  void warn(const std::string& message) { warn(message, std::chrono::steady_clock::now()); }
  void warn(const std::string& message, std::chrono::steady_clock::time_point now);

 private:
  Sink sink_;
  std::chrono::steady_clock::time_point last_{};
  bool logged_ = false;
  uint64_t held_ = 0;
};

// "1.5 s", "10 s": a duration as messages show it.
std::string seconds_text(double seconds);

}  // namespace lf

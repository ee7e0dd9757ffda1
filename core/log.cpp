#include "core/log.hpp"

#include <cstdio>
#include <cstdlib>

namespace lf {

static std::string g_name = "lightfarm";

void set_log_name(std::string name) { g_name = std::move(name); }

static LogObserver g_observer;

void set_log_observer(LogObserver observer) { g_observer = std::move(observer); }

static void emit(const char* level, const std::string& message, LogKind kind = LogKind::plain) {
  // One fprintf per line so lines from several processes sharing a terminal do not interleave mid-line.
  std::fprintf(stderr, "%s: %s%s\n", g_name.c_str(), level, message.c_str());
  if (g_observer) g_observer(level, message, kind);
}

std::string seconds_text(double seconds) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g s", seconds);
  return buf;
}

const char* log_kind_name(LogKind kind) {
  switch (kind) {
    case LogKind::loss: return "loss";
    case LogKind::recovery: return "recovery";
    case LogKind::plain: break;
  }
  return "plain";
}

void log_info(const std::string& m, LogKind kind) { emit("", m, kind); }
void log_warn(const std::string& m, LogKind kind) { emit("warning: ", m, kind); }
void log_error(const std::string& m) { emit("error: ", m); }
void log_debug(const std::string& m) {
  static const bool enabled = std::getenv("LIGHTFARM_DEBUG") != nullptr;
  if (enabled) emit("debug: ", m);
}

void RateLimitedLog::warn(const std::string& message, std::chrono::steady_clock::time_point now) {
  if (logged_ && now - last_ < std::chrono::seconds(1)) {
    ++held_;
    return;
  }
  sink_(held_ == 0 ? message : message + " (and " + std::to_string(held_) + " more like it in the last second)");
  held_ = 0;
  last_ = now;
  logged_ = true;
}

}  // namespace lf

#pragma once
// The live monitor (`lightfarm run --monitor [ADDR:]PORT`): a web page served by the director while the farm runs
// (after NetWatch in Kipfer, "Distributed Lighting Networks", 1999). cpp-httplib serves, on threads of its own:
//   /              the page (monitor_page.cpp: HTML, CSS and JS in the binary, nothing from elsewhere)
//   /events        Server-Sent Events: `state` (the JSON of /api/state) at least once a second and whenever it
//                  changes, `preview` as tiles land: the whole image once, then to each stream only the
//                  blocks that changed since the version it has (docs/monitor.md)
//   /api/state     the same state as one JSON document (docs/monitor.md)
//   /api/preview   the image so far, tone-mapped as the output will be: width x height 8-bit RGB, top row first
//   /metrics       per-actor counters in Prometheus' text format
// The director's loop publishes; readers never touch the farm, so a slow, vanished or numerous client costs the
// farm nothing but the copy of a string. Bound to 127.0.0.1 unless told otherwise; on any other address every
// request must carry the token printed at start (?token=...).
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "core/result.hpp"
#include "core/value.hpp"

namespace httplib {
class Server;
}

namespace lf {

class Monitor {
 public:
  // `address`: "PORT" or "ADDR:PORT"; port 0 picks a free one.
  static Result<std::unique_ptr<Monitor>> start(const std::string& address);
  ~Monitor();
  Monitor(const Monitor&) = delete;
  Monitor& operator=(const Monitor&) = delete;

  // The page's address, with the token when there is one.
  std::string url() const;
  int port() const { return port_; }

  // The farm's state (docs/monitor.md); wakes every /events stream.
  void publish_state(const Value& state);
  // The image so far: width x height 8-bit RGB, how many tiles it holds, when the first and the last of the tiles
  // new in it landed (Unix ms). Without `notify` the streams learn of it with the next publish_state().
  // Called from one thread (the director's loop).
  void publish_preview(int width, int height, std::string rgb, uint64_t tiles, int64_t first_landed_ms,
                       int64_t landed_ms, bool notify = true);
  // Clients connected to /events now, and ever.
  int streams() const { return streams_; }

 private:
  Monitor() = default;
  bool allowed(const std::string& token) const;
  std::string metrics_text(const Value& state) const;
  // The preview event for a stream that holds `version` (0: none): the blocks changed since, or the whole image.
  // Called with mutex_ held.
  const std::string& preview_event_after(uint64_t version);

  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
  std::string host_, token_;
  int port_ = 0;

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  bool stopping_ = false;
  std::string state_json_ = "{}", metrics_ = "";
  uint64_t state_version_ = 0;
  // The preview: its pixels; the event's fields other than the pixels; the blocks changed from the version before
  // (empty when there was none of the same size); the whole image as an event, built when first asked for.
  int preview_width_ = 0, preview_height_ = 0;
  std::string preview_rgb_, preview_head_, preview_delta_json_, preview_full_json_;
  uint64_t preview_version_ = 0, preview_full_version_ = 0;
  int streams_ = 0;
};

// The page itself (monitor_page.cpp).
extern const char* const kMonitorPage;

}  // namespace lf

#include "actors/monitor/monitor.hpp"

#include <httplib.h>
#include <openssl/evp.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <cstdio>
#include <fstream>

namespace lf {

namespace {

// 16 random hex digits from the kernel: the token a monitor bound beyond loopback asks for.
std::string random_token() {
  std::ifstream in("/dev/urandom", std::ios::binary);
  unsigned char b[8] = {};
  in.read(reinterpret_cast<char*>(b), sizeof b);
  char hex[17];
  for (int i = 0; i < 8; ++i) std::snprintf(hex + 2 * i, 3, "%02x", b[i]);
  return hex;
}

double number(const Value* v) {
  if (!v) return 0;
  if (v->is_int()) return static_cast<double>(v->as_int());
  if (v->is_double()) return v->as_double();
  return 0;
}

// A Prometheus label value: backslashes, quotes and newlines escaped.
std::string label(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '\\' || c == '"') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out;
}

std::string base64(const char* data, size_t n) {
  std::string out(4 * ((n + 2) / 3), '\0');
  const int written = EVP_EncodeBlock(reinterpret_cast<unsigned char*>(out.data()),
                                      reinterpret_cast<const unsigned char*>(data), static_cast<int>(n));
  out.resize(static_cast<size_t>(std::max(0, written)));
  return out;
}

struct Rect {
  int x, y, w, h;
};

// The 16x16 blocks in which two images of the same size differ, as rectangles: the changed blocks of each row of
// blocks, neighbours merged. Tiles land a few at a time, so a watching page is sent a small part of the image.
constexpr int kPreviewBlock = 16;

std::vector<Rect> changed_blocks(const std::string& before, const std::string& after, int width, int height) {
  std::vector<Rect> rects;
  const size_t row_bytes = static_cast<size_t>(width) * 3;
  for (int by = 0; by < height; by += kPreviewBlock) {
    const int bh = std::min(kPreviewBlock, height - by);
    for (int bx = 0; bx < width; bx += kPreviewBlock) {
      const int bw = std::min(kPreviewBlock, width - bx);
      bool changed = false;
      for (int y = by; y < by + bh && !changed; ++y) {
        const size_t at = y * row_bytes + static_cast<size_t>(bx) * 3;
        changed = std::memcmp(before.data() + at, after.data() + at, static_cast<size_t>(bw) * 3) != 0;
      }
      if (!changed) continue;
      if (!rects.empty() && rects.back().y == by && rects.back().x + rects.back().w == bx) rects.back().w += bw;
      else rects.push_back({bx, by, bw, bh});
    }
  }
  return rects;
}

// One rectangle of an image as the preview event carries it: {x, y, w, h, rgb (its rows, top first, in base64)}.
std::string patch_json(const std::string& rgb, int width, const Rect& r) {
  std::string pixels;
  pixels.reserve(static_cast<size_t>(r.w) * r.h * 3);
  for (int y = r.y; y < r.y + r.h; ++y)
    pixels.append(rgb, (static_cast<size_t>(y) * width + r.x) * 3, static_cast<size_t>(r.w) * 3);
  return "{\"x\":" + std::to_string(r.x) + ",\"y\":" + std::to_string(r.y) + ",\"w\":" + std::to_string(r.w) +
         ",\"h\":" + std::to_string(r.h) + ",\"rgb\":\"" + base64(pixels.data(), pixels.size()) + "\"}";
}

}  // namespace

Result<std::unique_ptr<Monitor>> Monitor::start(const std::string& address) {
  std::unique_ptr<Monitor> m(new Monitor());
  std::string port_text = address;
  m->host_ = "127.0.0.1";
  if (const auto colon = address.rfind(':'); colon != std::string::npos) {
    m->host_ = address.substr(0, colon);
    port_text = address.substr(colon + 1);
  }
  char* end = nullptr;
  const long port = std::strtol(port_text.c_str(), &end, 10);
  if (port_text.empty() || *end != '\0' || port < 0 || port > 65535)
    return make_error("--monitor '" + address + "': expected [ADDR:]PORT with a port from 0 to 65535");
  if (m->host_ != "127.0.0.1" && m->host_ != "localhost" && m->host_ != "::1") m->token_ = random_token();

  m->server_ = std::make_unique<httplib::Server>();
  httplib::Server& s = *m->server_;
  // SO_REUSEADDR only: cpp-httplib's default adds SO_REUSEPORT, which would let two servers share a port and
  // hide that it is in use.
  s.set_socket_options([](socket_t sock) {
    int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  // Every /events client holds a thread while it listens; 64 of them, and further requests queue.
  s.new_task_queue = [] { return new httplib::ThreadPool(64); };
  Monitor* self = m.get();
  auto guarded = [self](auto handler) {
    return [self, handler](const httplib::Request& req, httplib::Response& res) {
      if (!self->allowed(req.get_param_value("token"))) {
        res.status = 403;
        res.set_content("this monitor needs ?token=... (printed when the farm started)\n", "text/plain");
        return;
      }
      handler(req, res);
    };
  };
  s.Get("/", guarded([](const httplib::Request&, httplib::Response& res) {
    res.set_content(kMonitorPage, "text/html; charset=utf-8");
  }));
  s.Get("/api/state", guarded([self](const httplib::Request&, httplib::Response& res) {
    std::lock_guard<std::mutex> lock(self->mutex_);
    res.set_content(self->state_json_, "application/json");
  }));
  s.Get("/api/preview", guarded([self](const httplib::Request& req, httplib::Response& res) {
    std::lock_guard<std::mutex> lock(self->mutex_);
    res.set_header("Cache-Control", "no-cache");
    if (req.get_param_value("format") == "json")  // the preview event of a stream that has nothing yet
      res.set_content(self->preview_version_ ? self->preview_event_after(0) : "{}", "application/json");
    else
      res.set_content(self->preview_rgb_, "application/octet-stream");
  }));
  s.Get("/metrics", guarded([self](const httplib::Request&, httplib::Response& res) {
    std::lock_guard<std::mutex> lock(self->mutex_);
    res.set_content(self->metrics_, "text/plain; version=0.0.4");
  }));
  s.Get("/events", guarded([self](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-cache");
    {
      std::lock_guard<std::mutex> lock(self->mutex_);
      ++self->streams_;
    }
    // Per stream: the versions it has sent (0: nothing yet, so the first turn sends everything).
    auto sent = std::make_shared<std::pair<uint64_t, uint64_t>>(0, 0);
    res.set_chunked_content_provider(
        "text/event-stream",
        [self, sent](size_t, httplib::DataSink& sink) {
          std::string out;
          {
            std::unique_lock<std::mutex> lock(self->mutex_);
            self->changed_.wait_for(lock, std::chrono::seconds(1), [&] {
              return self->stopping_ || self->state_version_ != sent->first || self->preview_version_ != sent->second;
            });
            if (self->stopping_) return false;
            // A state event at least once a second (the page's clock), the preview only when it changed.
            out = "event: state\ndata: " + self->state_json_ + "\n\n";
            sent->first = self->state_version_;
            if (self->preview_version_ != sent->second) {
              out += "event: preview\ndata: " + self->preview_event_after(sent->second) + "\n\n";
              sent->second = self->preview_version_;
            }
          }
          // A client that went away fails the write: the stream ends, and only this thread notices.
          return sink.is_writable() && sink.write(out.data(), out.size());
        },
        [self](bool) {
          std::lock_guard<std::mutex> lock(self->mutex_);
          --self->streams_;
        });
  }));

  if (port == 0) {
    m->port_ = s.bind_to_any_port(m->host_);
    if (m->port_ < 0) return make_error("--monitor: cannot listen on " + m->host_);
  } else {
    if (!s.bind_to_port(m->host_, static_cast<int>(port)))
      return make_error("--monitor: cannot listen on " + m->host_ + ":" + port_text +
                        " (in use, or not an address of this machine)");
    m->port_ = static_cast<int>(port);
  }
  m->thread_ = std::thread([self] { self->server_->listen_after_bind(); });
  return m;
}

Monitor::~Monitor() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  if (server_) server_->stop();
  if (thread_.joinable()) thread_.join();
}

bool Monitor::allowed(const std::string& token) const { return token_.empty() || token == token_; }

std::string Monitor::url() const {
  const std::string host = host_ == "0.0.0.0" ? "HOST" : host_;
  return "http://" + host + ":" + std::to_string(port_) + "/" + (token_.empty() ? "" : "?token=" + token_);
}

void Monitor::publish_state(const Value& state) {
  std::string json = to_json(state);
  std::string metrics = metrics_text(state);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    state_json_ = std::move(json);
    metrics_ = std::move(metrics);
    ++state_version_;
  }
  changed_.notify_all();
}

void Monitor::publish_preview(int width, int height, std::string rgb, uint64_t tiles, int64_t first_landed_ms,
                              int64_t landed_ms, bool notify) {
  // Only this thread writes the pixels, so it may read them without the lock while it builds the next event.
  const uint64_t version = preview_version_ + 1;
  std::string head = "{\"width\":" + std::to_string(width) + ",\"height\":" + std::to_string(height) +
                     ",\"tiles\":" + std::to_string(tiles) + ",\"first_landed_ms\":" + std::to_string(first_landed_ms) +
                     ",\"landed_ms\":" + std::to_string(landed_ms) + ",\"version\":" + std::to_string(version);
  std::string delta;
  if (preview_version_ && width == preview_width_ && height == preview_height_ && rgb.size() == preview_rgb_.size()) {
    delta = head + ",\"base\":" + std::to_string(preview_version_) + ",\"patches\":[";
    bool first = true;
    for (const Rect& r : changed_blocks(preview_rgb_, rgb, width, height)) {
      if (!first) delta += ',';
      first = false;
      delta += patch_json(rgb, width, r);
    }
    delta += "]}";
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    preview_version_ = version;
    preview_width_ = width;
    preview_height_ = height;
    preview_rgb_ = std::move(rgb);
    preview_head_ = std::move(head);
    preview_delta_json_ = std::move(delta);
  }
  if (notify) changed_.notify_all();
}

const std::string& Monitor::preview_event_after(uint64_t version) {
  if (version && version + 1 == preview_version_ && !preview_delta_json_.empty()) return preview_delta_json_;
  if (preview_full_version_ != preview_version_) {
    preview_full_version_ = preview_version_;
    preview_full_json_ = preview_head_ + ",\"base\":0,\"patches\":[" +
                         patch_json(preview_rgb_, preview_width_, Rect{0, 0, preview_width_, preview_height_}) + "]}";
  }
  return preview_full_json_;
}

std::string Monitor::metrics_text(const Value& state) const {
  std::string out;
  const Value* farm = state.find("farm");
  auto gauge = [&](const std::string& name, const std::string& help, const std::string& type) {
    out += "# HELP lightfarm_" + name + " " + help + "\n# TYPE lightfarm_" + name + " " + type + "\n";
  };
  gauge("tiles_done", "tiles finished", "gauge");
  out += "lightfarm_tiles_done " + std::to_string(number(farm ? farm->find("tiles_done") : nullptr)) + "\n";
  gauge("tiles_total", "tiles in the frame", "gauge");
  out += "lightfarm_tiles_total " + std::to_string(number(farm ? farm->find("tiles_total") : nullptr)) + "\n";
  gauge("elapsed_seconds", "seconds since the farm started", "gauge");
  out += "lightfarm_elapsed_seconds " + std::to_string(number(farm ? farm->find("elapsed_seconds") : nullptr)) + "\n";
  const Value* actors = state.find("actors");
  struct Series {
    const char* key;
    const char* name;
    const char* help;
    const char* type;
  };
  static const Series series[] = {
      {"requests", "actor_requests_total", "requests served (LightOps) or sent (renderers)", "counter"},
      {"points", "actor_points_total", "shading points shaded or traced", "counter"},
      {"tiles", "actor_tiles_total", "tiles rendered (renderers)", "counter"},
      {"busy_seconds", "actor_busy_seconds_total", "seconds inside handlers", "counter"},
      {"queue", "actor_queue", "requests waiting now", "gauge"},
      {"bytes_in", "actor_bytes_in_total", "bytes received", "counter"},
      {"bytes_out", "actor_bytes_out_total", "bytes sent", "counter"}};
  for (const Series& s : series) {
    gauge(s.name, s.help, s.type);
    if (!actors || !actors->is_array()) continue;
    for (const Value& a : actors->as_array()) {
      const Value* name = a.find("name");
      const Value* live = a.find("live");
      if (!name || !name->is_string()) continue;
      out += std::string("lightfarm_") + s.name + "{actor=\"" + label(name->as_string()) + "\",kind=\"" +
             label(a.find("kind") && a.find("kind")->is_string() ? a.find("kind")->as_string() : "") + "\"} " +
             std::to_string(number(live ? live->find(s.key) : nullptr)) + "\n";
    }
  }
  gauge("actor_lost", "1 when the actor was lost", "gauge");
  if (actors && actors->is_array())
    for (const Value& a : actors->as_array()) {
      const Value* name = a.find("name");
      const Value* st = a.find("state");
      if (!name || !name->is_string()) continue;
      out += "lightfarm_actor_lost{actor=\"" + label(name->as_string()) + "\"} " +
             (st && st->is_string() && st->as_string() == "lost" ? "1" : "0") + "\n";
    }
  return out;
}

}  // namespace lf

// The monitor's preview stream: a stream gets the whole image first, then only the blocks that changed since the
// version it holds, and applying them gives the image exactly; a stream that joins late, and /api/preview, get the
// whole image.
#include "actors/monitor/monitor.hpp"

#include <gtest/gtest.h>
#include <httplib.h>
#include <openssl/evp.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <random>
#include <regex>
#include <thread>

namespace lf {
namespace {

struct Patch {
  int x, y, w, h;
  std::string rgb;
};

struct PreviewEvent {
  uint64_t version = 0, base = 0;
  std::vector<Patch> patches;
};

uint64_t field(const std::string& json, const std::string& name) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + name + "\":([0-9]+)"))) return UINT64_MAX;
  return std::stoull(m[1]);
}

PreviewEvent parse_preview(const std::string& json) {
  PreviewEvent e;
  e.version = field(json, "version");
  e.base = field(json, "base");
  const std::regex patch("\\{\"x\":([0-9]+),\"y\":([0-9]+),\"w\":([0-9]+),\"h\":([0-9]+),\"rgb\":\"([^\"]*)\"\\}");
  for (auto it = std::sregex_iterator(json.begin(), json.end(), patch); it != std::sregex_iterator(); ++it) {
    const auto& m = *it;
    Patch p{std::stoi(m[1]), std::stoi(m[2]), std::stoi(m[3]), std::stoi(m[4]), {}};
    const std::string text = m[5];
    std::string bytes(3 * text.size() / 4 + 3, '\0');
    const int n = EVP_DecodeBlock(reinterpret_cast<unsigned char*>(bytes.data()),
                                  reinterpret_cast<const unsigned char*>(text.data()), static_cast<int>(text.size()));
    EXPECT_GE(n, 0);
    bytes.resize(static_cast<size_t>(p.w) * p.h * 3);  // EVP_DecodeBlock counts the padding's zero bytes too
    p.rgb = bytes;
    e.patches.push_back(p);
  }
  return e;
}

void apply(const PreviewEvent& e, int width, std::string& image) {
  for (const Patch& p : e.patches)
    for (int y = 0; y < p.h; ++y)
      image.replace((static_cast<size_t>(p.y + y) * width + p.x) * 3, static_cast<size_t>(p.w) * 3, p.rgb,
                    static_cast<size_t>(y) * p.w * 3, static_cast<size_t>(p.w) * 3);
}

// An /events client on a thread of its own, keeping the preview events it receives.
class Stream {
 public:
  explicit Stream(int port) {
    thread_ = std::thread([this, port] {
      httplib::Client c("127.0.0.1", port);
      c.set_read_timeout(30, 0);
      std::string buffer;
      c.Get("/events", [&](const char* data, size_t n) {
        buffer.append(data, n);
        for (size_t end; (end = buffer.find("\n\n")) != std::string::npos; buffer.erase(0, end + 2)) {
          const std::string event = buffer.substr(0, end);
          const std::string head = "event: preview\ndata: ";
          if (event.rfind(head, 0) != 0) continue;
          std::lock_guard<std::mutex> lock(mutex_);
          previews_.push_back(event.substr(head.size()));
        }
        return !stop_;
      });
    });
  }
  ~Stream() {
    stop_ = true;
    thread_.join();
  }
  // The n-th preview event (from 0), waiting up to 10 s for it.
  std::string preview(size_t n) {
    for (int i = 0; i < 1000; ++i) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (previews_.size() > n) return previews_[n];
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return "";
  }

 private:
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::vector<std::string> previews_;
};

std::string noise_image(int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::string rgb(static_cast<size_t>(width) * height * 3, '\0');
  for (char& c : rgb) c = static_cast<char>(rng() & 0xff);
  return rgb;
}

TEST(MonitorPreview, AStreamGetsTheWholeImageThenOnlyTheBlocksThatChanged) {
  auto started = Monitor::start("127.0.0.1:0");
  ASSERT_TRUE(started) << started.error().message;
  Monitor& monitor = **started;
  // 40 x 24: the last block column and row are partial (blocks are 16 x 16).
  const int w = 40, h = 24;
  const std::string a = noise_image(w, h, 1);
  monitor.publish_preview(w, h, a, 3, 1000, 1001);

  Stream first(monitor.port());
  const PreviewEvent whole = parse_preview(first.preview(0));
  EXPECT_EQ(whole.base, 0u);
  ASSERT_EQ(whole.patches.size(), 1u);
  EXPECT_EQ(whole.patches[0].w, w);
  EXPECT_EQ(whole.patches[0].h, h);
  std::string shown(a.size(), '\0');
  apply(whole, w, shown);
  EXPECT_EQ(shown, a);

  // Changes in the first block, in its right neighbour (merged with it) and in the partial corner block.
  std::string b = a;
  for (const auto& [x, y] : std::vector<std::pair<int, int>>{{0, 0}, {17, 3}, {20, 5}, {39, 23}})
    b[(static_cast<size_t>(y) * w + x) * 3 + 1] ^= 0x5a;
  monitor.publish_preview(w, h, b, 5, 2000, 2001);
  const PreviewEvent delta = parse_preview(first.preview(1));
  EXPECT_EQ(delta.base, whole.version);
  EXPECT_EQ(delta.version, whole.version + 1);
  ASSERT_EQ(delta.patches.size(), 2u);
  EXPECT_EQ(std::make_tuple(delta.patches[0].x, delta.patches[0].y, delta.patches[0].w, delta.patches[0].h),
            std::make_tuple(0, 0, 32, 16));
  EXPECT_EQ(std::make_tuple(delta.patches[1].x, delta.patches[1].y, delta.patches[1].w, delta.patches[1].h),
            std::make_tuple(32, 16, 8, 8));
  apply(delta, w, shown);
  EXPECT_EQ(shown, b) << "the changed blocks turn the first image into the second";

  // A stream that joins now starts from the whole image, as does /api/preview.
  Stream late(monitor.port());
  const PreviewEvent late_whole = parse_preview(late.preview(0));
  EXPECT_EQ(late_whole.base, 0u);
  EXPECT_EQ(late_whole.version, delta.version);
  std::string late_shown(b.size(), '\0');
  apply(late_whole, w, late_shown);
  EXPECT_EQ(late_shown, b);
  httplib::Client c("127.0.0.1", monitor.port());
  auto raw = c.Get("/api/preview");
  ASSERT_TRUE(raw);
  EXPECT_EQ(raw->body, b);
  auto json = c.Get("/api/preview?format=json");
  ASSERT_TRUE(json);
  EXPECT_EQ(field(json->body, "base"), 0u);
  EXPECT_EQ(field(json->body, "version"), delta.version);

  // The same image again: an event with nothing to change.
  monitor.publish_preview(w, h, b, 5, 3000, 3001);
  const PreviewEvent same = parse_preview(first.preview(2));
  EXPECT_EQ(same.base, delta.version);
  EXPECT_TRUE(same.patches.empty());
}

// A new size (another frame's image) is sent whole, even to a stream that holds the version before.
TEST(MonitorPreview, ANewSizeIsSentWhole) {
  auto started = Monitor::start("127.0.0.1:0");
  ASSERT_TRUE(started) << started.error().message;
  Monitor& monitor = **started;
  monitor.publish_preview(16, 16, noise_image(16, 16, 2), 1, 1, 1);
  Stream s(monitor.port());
  EXPECT_EQ(parse_preview(s.preview(0)).base, 0u);
  const std::string bigger = noise_image(20, 18, 3);
  monitor.publish_preview(20, 18, bigger, 2, 2, 2);
  const PreviewEvent e = parse_preview(s.preview(1));
  EXPECT_EQ(e.base, 0u);
  ASSERT_EQ(e.patches.size(), 1u);
  std::string shown(bigger.size(), '\0');
  apply(e, 20, shown);
  EXPECT_EQ(shown, bigger);
}

}  // namespace
}  // namespace lf

#pragma once
// A job's carried setups (LightOp::carries_views: a camera-placed irradiance cache, learned lights, kept over the
// frames), kept in its record's folder after each view, so that a run resuming the job restores them instead of
// replaying the views of every frame before its first. Serves
//   keep_setup {frame: int, state: bin} -> {}   an actor's carried setup, as extended to that frame's view
// One file per actor and frame, OUTPUT.lfjob/setups/<actor>.<frame>.setup:
//   "LFSETUP1\n" <actor> "\n" <key> "\n" <checksum of the whole state> "\n" <base frame> " " <base length> "\n" <bytes>
// (the key: what the state depends on, setup_keys: every view of the job up to that frame and whatever a frame's
// key holds). A carried setup only grows (records are added, never moved), so a state that begins with the one this
// run kept before it is kept as what it adds: <bytes> follow the first <base length> bytes of the state kept for
// <base frame> (base frame "-": none, the bytes are the whole state). Every frame's state stays findable for what
// the job's final state weighs. A file counts only with the actor's name, the key the frame has now, a whole
// chain of bases and the state's checksum.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "actors/director/service.hpp"
#include "farm/farm_spec.hpp"

namespace lf {

// What the carried setup after a frame depends on: the views of every frame of the job up to it (the setup is
// extended to each in turn) and what frame_key holds for each. `previous`: the key of the frame before (empty for
// the job's first), `frame`: this frame's frame_key.
std::string setup_key(const std::string& previous, const std::string& frame);

class CarriedSetups final : public Service {
 public:
  // Keeps setups in `folder` (the job record's): for frame number n, the key keys_by_frame[n].
  void begin(std::string folder, std::map<int, std::string> keys_by_frame);
  std::vector<wire::Op> ops() const override { return {wire::Op::keep_setup}; }
  Status on_request(const std::string& actor, wire::Op op, uint64_t id, Value body, Outbox& out) override;

  // The state kept for `actor` at frame `number` if there is a whole one with the frame's key.
  std::optional<std::string> find(const std::string& actor, int number) const;
  // `actor`'s setup was restored from `state`, kept for frame `number`: what this run keeps next grows from it.
  void restored(const std::string& actor, int number, const std::string& state);
  // --restart: every kept setup is forgotten.
  static void clear(const std::string& folder);
  size_t kept() const { return kept_; }
  uint64_t bytes_kept() const { return bytes_kept_; }

 private:
  std::string path(const std::string& actor, int number) const;
  std::string folder_;
  std::map<int, std::string> keys_;
  struct Last {
    int frame = 0;
    size_t length = 0;
    std::string prefix_hash;  // of the whole state kept for `frame`
  };
  std::map<std::string, Last> last_;  // actor -> what this run kept for it last
  size_t kept_ = 0;
  uint64_t bytes_kept_ = 0;
};

}  // namespace lf

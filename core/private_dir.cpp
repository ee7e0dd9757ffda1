#include "core/private_dir.hpp"

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <vector>

namespace lf {

namespace {
const char* const kTmp = "/tmp";
std::string prefix(const std::string& kind) { return "lightfarm-" + kind + "-"; }
}  // namespace

std::string make_private_dir(const std::string& kind) {
  std::string templ = std::string(kTmp) + "/" + prefix(kind) + std::to_string(::getpid()) + "-XXXXXX";
  std::vector<char> buffer(templ.begin(), templ.end());
  buffer.push_back('\0');
  return ::mkdtemp(buffer.data()) ? std::string(buffer.data()) : std::string();
}

bool owner_is_gone(std::string_view pid) {
  if (pid.empty() || pid.size() > 9 || pid.find_first_not_of("0123456789") != std::string_view::npos) return false;
  return ::kill(static_cast<pid_t>(std::stol(std::string(pid))), 0) != 0 && errno == ESRCH;
}

int sweep_stale_private_dirs(const std::string& kind) {
  namespace fs = std::filesystem;
  const std::string start = prefix(kind);
  std::error_code ec;
  int swept = 0;
  for (fs::directory_iterator it(kTmp, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(start, 0) != 0) continue;
    const std::string rest = name.substr(start.size());
    const auto dash = rest.find('-');
    if (dash == std::string::npos) continue;
    struct stat st {};
    if (::lstat(it->path().c_str(), &st) != 0 || !S_ISDIR(st.st_mode) || st.st_uid != ::getuid()) continue;
    if (!owner_is_gone(std::string_view(rest).substr(0, dash))) continue;
    std::error_code rm;
    fs::remove_all(it->path(), rm);
    if (!rm) ++swept;
  }
  return swept;
}

}  // namespace lf

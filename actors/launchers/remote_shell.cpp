#include "actors/launchers/remote_shell.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <chrono>
#include <thread>

namespace lf {

using Clock = std::chrono::steady_clock;

// Runs argv with stdout and stderr captured, `input` on its stdin (else /dev/null), for at most `seconds`.
Captured run_captured(const std::vector<std::string>& argv, double seconds, const std::string* input) {
  Captured c;
  int out[2], in[2] = {-1, -1};
  if (::pipe2(out, O_CLOEXEC) != 0) return c;
  const pid_t pid = (input && ::pipe2(in, O_CLOEXEC) != 0) ? -1 : ::fork();
  if (pid < 0) {  // never go on to waitpid(-1, ...): that would reap one of the farm's actors
    for (int fd : {out[0], out[1], in[0], in[1]})
      if (fd >= 0) ::close(fd);
    c.output = std::string("cannot start ") + argv[0] + ": " + std::strerror(errno);
    return c;
  }
  if (pid == 0) {
    ::dup2(out[1], STDOUT_FILENO);
    ::dup2(out[1], STDERR_FILENO);
    if (input) {
      ::dup2(in[0], STDIN_FILENO);
    } else {
      const int null = ::open("/dev/null", O_RDONLY);
      if (null >= 0) ::dup2(null, STDIN_FILENO);
    }
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execvp(args[0], args.data());
    ::_exit(127);
  }
  c.ran = true;
  ::close(out[1]);
  std::thread writer;
  if (input) {
    ::close(in[0]);
    // A writer of its own, so that a large scene and the child's output never wait on each other.
    writer = std::thread([fd = in[1], input] {
      for (size_t done = 0; done < input->size();) {
        const ssize_t w = ::write(fd, input->data() + done, input->size() - done);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) break;
        done += static_cast<size_t>(w);
      }
      ::close(fd);
    });
  }
  ::fcntl(out[0], F_SETFL, O_NONBLOCK);
  const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
  char buf[4096];
  bool exited = false;
  while (true) {
    ssize_t n;
    while ((n = ::read(out[0], buf, sizeof buf)) > 0) c.output.append(buf, static_cast<size_t>(n));
    if (!exited && ::waitpid(pid, &c.status, WNOHANG) == pid) exited = true;
    // A ControlPersist master inherits the pipe, so EOF may never come: the child's exit is enough.
    if (exited) break;
    if (Clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
      c.status = -1;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ssize_t n;
  while ((n = ::read(out[0], buf, sizeof buf)) > 0) c.output.append(buf, static_cast<size_t>(n));
  ::close(out[0]);
  if (writer.joinable()) writer.join();  // the child is gone: its end of the pipe is closed, the write returned
  return c;
}

std::string last_line(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  const auto nl = text.rfind('\n');
  return nl == std::string::npos ? text : text.substr(nl + 1);
}


std::string shell_quote(const std::string& text) {
  std::string q = "'";
  for (char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string cache_check_script(const std::string& hash, size_t size) {
  return std::string(kCacheDir) + "f=\"$d/" + hash + ".lfscene\"; if [ -f \"$f\" ] && [ \"$(wc -c < \"$f\")\" -eq " +
         std::to_string(size) + " ]; then echo \"have $f\"; else echo \"need $f\"; fi";
}

std::string cache_write_script(const std::string& hash) {
  return std::string(kCacheDir) + "f=\"$d/" + hash +
         ".lfscene\"; mkdir -p \"$d\" && cat > \"$f.partial.$$\" && mv -f \"$f.partial.$$\" \"$f\" && echo \"got $f\"";
}

Result<Launcher::Shipped> ship_through(const std::vector<std::string>& prefix, const std::string& who,
                                       const std::string& bytes, const std::string& hash) {
  auto argv = prefix;
  argv.push_back(cache_check_script(hash, bytes.size()));
  const Captured check = run_captured(argv, 30.0);
  const auto have = check.output.find("have ");
  if (have != std::string::npos) return Launcher::Shipped{last_line(check.output.substr(have + 5)), 0};
  if (check.output.find("need ") == std::string::npos)
    return make_error(who + ": cannot look into its scene cache: " + last_line(check.output));
  argv.back() = cache_write_script(hash);
  const Captured sent = run_captured(argv, 600.0, &bytes);
  const auto got = sent.output.find("got ");
  if (got == std::string::npos) return make_error(who + ": cannot ship the scene: " + last_line(sent.output));
  return Launcher::Shipped{last_line(sent.output.substr(got + 4)), bytes.size()};
}

}  // namespace lf

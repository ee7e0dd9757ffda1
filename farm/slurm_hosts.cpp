#include "farm/slurm_hosts.hpp"

#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace lf {

namespace {

// stdout of a shell command, and whether it succeeded.
bool capture(const std::string& command, std::string& out) {
  FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (!p) return false;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  return ::pclose(p) == 0;
}

std::string quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace

Result<std::vector<HostSpec>> slurm_allocation_hosts() {
  const char* list = std::getenv("SLURM_JOB_NODELIST");
  if (!list || !*list) list = std::getenv("SLURM_NODELIST");
  if (!list || !*list)
    return make_error("slurm_hosts(): not inside a Slurm allocation (SLURM_JOB_NODELIST is not set; run the farm "
                      "under salloc or sbatch)");
  std::string names;
  if (!capture("scontrol show hostnames " + quoted(list), names))
    return make_error("slurm_hosts(): scontrol could not expand '" + std::string(list) + "': " + names);
  std::vector<HostSpec> hosts;
  std::istringstream in(names);
  for (std::string node; in >> node;) {
    std::string info;
    if (!capture("scontrol show node " + quoted(node) + " -o", info))
      return make_error("slurm_hosts(): scontrol knows no node '" + node + "': " + info);
    HostSpec h;
    h.name = node;
    h.launcher = "slurm";
    const auto at = info.find("NodeAddr=");
    h.address = at == std::string::npos ? node : info.substr(at + 9, info.find_first_of(" \n", at) - at - 9);
    hosts.push_back(h);
  }
  if (hosts.empty()) return make_error("slurm_hosts(): the allocation '" + std::string(list) + "' has no nodes");
  return hosts;
}

}  // namespace lf

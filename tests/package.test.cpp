// The Debian package for farm nodes (README, "Farm nodes"): cpack makes it from this build; it declares the runtime
// libraries the binary and its modules link, holds the binary, the modules, the SDK and the docs, and the binary it
// installs renders an example with its image module taken from the package's own folder, leaving nothing running.
#include <cstdio>

#include "tests/farm_harness.hpp"

namespace lf::test {
namespace {

struct Output {
  int status = -1;
  std::string text;  // stdout and stderr together
};

// Runs a shell command line, capturing what it prints.
Output shell(const std::string& command) {
  Output o;
  FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (!p) return o;
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, p)) > 0) o.text.append(buffer, n);
  const int st = ::pclose(p);
  o.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return o;
}

std::string single_quoted(const std::string& s) { return "'" + s + "'"; }

class Package : public FarmFixture {};

TEST_F(Package, ADebianPackageInstallsAFarmNode) {
  if (shell("command -v dpkg-deb && command -v dpkg-shlibdeps").status != 0)
    GTEST_SKIP() << "no dpkg-deb or dpkg-shlibdeps (dpkg-dev)";
  const Output made = shell(std::string(LIGHTFARM_CPACK) + " --config " + single_quoted(std::string(LIGHTFARM_BUILD_DIR) + "/CPackConfig.cmake") +
                            " -B " + single_quoted(path("pkg")));
  ASSERT_EQ(made.status, 0) << made.text;
  std::string deb;
  for (const auto& e : fs::directory_iterator(dir / "pkg"))
    if (e.path().extension() == ".deb") deb = e.path().string();
  ASSERT_FALSE(deb.empty()) << made.text;
  EXPECT_NE(deb.find("lightfarm_"), std::string::npos);
  EXPECT_NE(deb.find("_amd64.deb"), std::string::npos) << deb;

  const Output depends = shell("dpkg-deb -f " + single_quoted(deb) + " Depends");
  ASSERT_EQ(depends.status, 0) << depends.text;
  for (const char* library : {"libzmq5", "libembree3-3", "liblua5.4-0", "libopenimageio", "libopenexr", "libtinygltf"})
    EXPECT_NE(depends.text.find(library), std::string::npos) << library << " not among: " << depends.text;

  const Output listing = shell("dpkg-deb -c " + single_quoted(deb));
  ASSERT_EQ(listing.status, 0) << listing.text;
  for (const char* file : {"./usr/bin/lightfarm", "./usr/lib/lightfarm/liblightfarm_exr_png.so",
                           "./usr/lib/lightfarm/liblightfarm_imageio.so", "./usr/lib/cmake/lightfarm/lightfarmConfig.cmake",
                           "./usr/include/lightfarm/render/lightops/lightop.hpp",
                           "./usr/share/doc/lightfarm/examples/cornell.lua", "./usr/share/doc/lightfarm/PROTOCOL.md"})
    EXPECT_NE(listing.text.find(std::string(file) + "\n"), std::string::npos) << file;

  // Unpacked where a node would have it, under a root of its own.
  const fs::path root = dir / "root";
  ASSERT_EQ(shell("dpkg-deb -x " + single_quoted(deb) + " " + single_quoted(root.string())).status, 0);
  const std::string installed = (root / "usr/bin/lightfarm").string();
  const Output version = shell(single_quoted(installed) + " --version"), built = shell(std::string(LIGHTFARM_BINARY) + " --version");
  EXPECT_EQ(version.status, 0);
  EXPECT_EQ(version.text, built.text);

  // The loader's record of what it opened: the image module from the package, not from this build.
  const std::string tag = unique_tag();
  const Output run = shell("LD_DEBUG=files LIGHTFARM_TEST_TAG=" + tag + " " + single_quoted(installed) + " run " +
                           single_quoted((root / "usr/share/doc/lightfarm/examples/cornell.lua").string()) +
                           " --set spp=1 --set width=32 --set height=32 --quiet --output " + single_quoted(path("c.png")));
  EXPECT_EQ(run.status, 0) << run.text.substr(run.text.size() > 4000 ? run.text.size() - 4000 : 0);
  EXPECT_TRUE(fs::exists(path("c.png")));
  const std::string packaged_module = (root / "usr/bin/../lib/lightfarm/liblightfarm_exr_png.so").string();
  EXPECT_NE(run.text.find("file=" + packaged_module), std::string::npos);
  EXPECT_EQ(run.text.find(std::string("file=") + LIGHTFARM_BUILD_DIR + "/liblightfarm_exr_png.so"), std::string::npos);
  auto left = wait_no_leftovers(tag);
  EXPECT_TRUE(left.empty()) << left.size() << " lightfarm processes left behind";
}

}  // namespace
}  // namespace lf::test

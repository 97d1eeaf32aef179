// Installing without root (#15 item 7): `cmake --install` puts cellbake,
// cellbake-view, the configurations and the docs under a prefix, and the
// installed `cellbake view` finds its viewer; a plain configure builds no tests
// or benchmarks; scripts/install-deps.sh runs no apt-get when nothing is
// missing, asks the plain build for no Slurm daemons or Xvfb, and without root
// or sudo prints the apt-get line to run.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <set>

#include "test_support.h"

namespace cellbake {
namespace {

using test::count_of;
using test::read_text;

const std::filesystem::path kSource = std::filesystem::path(CELLBAKE_SOURCE_DIR);

test::CommandResult shell(const std::string& command) { return test::run_shell(command); }

std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

TEST(Install, PrefixGetsCellbakeItsViewerConfigsAndDocs) {
  test::TempDir dir;
  const std::filesystem::path prefix = dir / "home/.local";
  const auto install = shell("cmake --install " + q(CELLBAKE_BUILD_DIR) + " --prefix " + q(prefix));
  ASSERT_EQ(install.exit_code, 0) << install.output;
  EXPECT_TRUE(std::filesystem::exists(prefix / "bin/cellbake")) << install.output;
  EXPECT_TRUE(std::filesystem::exists(prefix / "share/cellbake/configs/plant-demo.toml")) << install.output;
  EXPECT_TRUE(std::filesystem::exists(prefix / "share/doc/cellbake/README.md")) << install.output;
  EXPECT_TRUE(std::filesystem::exists(prefix / "share/doc/cellbake/architecture.md")) << install.output;
  EXPECT_FALSE(std::filesystem::exists(prefix / "bin/cellbake-view"));  // an implementation detail of `view`
  const auto version = shell(q(prefix / "bin/cellbake") + " -V");
  EXPECT_EQ(version.exit_code, 0) << version.output;

  if (!std::filesystem::exists(std::filesystem::path(CELLBAKE_BINARY).parent_path() / "cellbake-view"))
    GTEST_SKIP() << "cellbake-view is not built here (no GLFW / Dear ImGui)";
  EXPECT_TRUE(std::filesystem::exists(prefix / "libexec/cellbake/cellbake-view")) << install.output;
  // The installed cellbake runs the installed viewer (--help-viewer: its help, no window needed).
  const auto view = shell(q(prefix / "bin/cellbake") + " view --help-viewer");
  EXPECT_EQ(view.exit_code, 0) << view.output;
  EXPECT_NE(view.output.find(prefix.string() + "/libexec/cellbake/cellbake-view"), std::string::npos) << view.output;
}

TEST(Install, ViewWithoutItsViewerNamesWhereItLooked) {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "bin");
  std::filesystem::copy_file(CELLBAKE_BINARY, dir / "bin/cellbake");
  const auto r = shell(q(dir / "bin/cellbake") + " view cells.db");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("cellbake-view not found"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find((dir / "bin/cellbake-view").string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find((dir / "libexec/cellbake/cellbake-view").string()), std::string::npos) << r.output;
}

TEST(Install, APlainConfigureBuildsNoTestsOrBenchmarks) {
  test::TempDir dir;
  const auto configure = shell("cmake -S " + q(kSource) + " -B " + q(dir / "build") + " -G Ninja");
  ASSERT_EQ(configure.exit_code, 0) << configure.output;
  const std::string cache = read_text(dir / "build/CMakeCache.txt");
  EXPECT_NE(cache.find("CELLBAKE_BUILD_TESTS:BOOL=OFF"), std::string::npos);
  EXPECT_NE(cache.find("CELLBAKE_BUILD_BENCH:BOOL=OFF"), std::string::npos);
  const auto targets = shell("ninja -C " + q(dir / "build") + " -t targets all");
  ASSERT_EQ(targets.exit_code, 0) << targets.output;
  EXPECT_NE(targets.output.find("runner/cellbake:"), std::string::npos) << targets.output;
  EXPECT_EQ(targets.output.find("test_bake"), std::string::npos);
  EXPECT_EQ(targets.output.find("bench_sample"), std::string::npos);
}

// A PATH of stand-ins for scripts/install-deps.sh: dpkg-query answers from
// `installed` (every package when it is "*") and logs what it was asked,
// id says `uid`, apt-get and sudo log their calls; grep is the real one.
class FakeDebian {
 public:
  FakeDebian(const test::TempDir& dir, const std::string& installed, int uid, bool sudo) : bin_(dir / "fakebin") {
    std::filesystem::create_directories(bin_);
    log_ = dir / "calls.log";
    script("dpkg-query", "for p; do :; done; echo \"dpkg-query $p\" >> " + q(log_) + "\n" +
                             (installed == "*" ? std::string("echo 'install ok installed'; exit 0\n")
                                               : "case \" " + installed +
                                                     " \" in *\" $p \"*) echo 'install ok installed'; exit 0;; esac; exit 1\n"));
    script("id", "echo " + std::to_string(uid) + "\n");
    script("apt-get", "echo \"apt-get $*\" >> " + q(log_) + "\n");
    if (sudo) script("sudo", "echo \"sudo $*\" >> " + q(log_) + "\n\"$@\"\n");
    std::filesystem::create_symlink("/usr/bin/grep", bin_ / "grep");
    std::filesystem::create_symlink("/usr/bin/env", bin_ / "env");
  }
  test::CommandResult run(const std::string& args) const {
    return shell("PATH=" + q(bin_) + " /bin/bash " + q(kSource / "scripts/install-deps.sh") + " " + args);
  }
  std::string calls() const { return read_text(log_); }

 private:
  void script(const std::string& name, const std::string& body) const {
    test::write_text(bin_ / name, "#!/bin/bash\n" + body);
    std::filesystem::permissions(bin_ / name, std::filesystem::perms::owner_all, std::filesystem::perm_options::add);
  }
  std::filesystem::path bin_, log_;
};

std::set<std::string> asked_packages(const std::string& calls) {
  std::set<std::string> names;
  std::istringstream in(calls);
  for (std::string line; std::getline(in, line);)
    if (line.rfind("dpkg-query ", 0) == 0) names.insert(line.substr(11));
  return names;
}

TEST(InstallDeps, NothingMissingMeansNoAptGet) {
  test::TempDir dir;
  const FakeDebian debian(dir, "*", 1000, false);
  const auto r = debian.run("");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("packages present"), std::string::npos) << r.output;
  EXPECT_EQ(debian.calls().find("apt-get"), std::string::npos) << debian.calls();
  // The plain build asks for no Slurm daemons, no Xvfb, no test frameworks.
  const std::set<std::string> asked = asked_packages(debian.calls());
  EXPECT_TRUE(asked.count("libtbb-dev")) << debian.calls();
  for (const char* other : {"slurmctld", "slurmd", "munge", "xvfb", "libgtest-dev", "libbenchmark-dev"})
    EXPECT_FALSE(asked.count(other)) << other;
}

TEST(InstallDeps, NotRootWithoutSudoPrintsTheAptGetLine) {
  test::TempDir dir;
  const FakeDebian debian(dir, "munge", 1000, false);
  const auto r = debian.run("slurm");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("apt-get update && apt-get install -y --no-install-recommends slurmctld slurmd slurm-client\n"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("not root and no sudo"), std::string::npos) << r.output;
  EXPECT_EQ(debian.calls().find("apt-get"), std::string::npos) << debian.calls();
}

TEST(InstallDeps, MissingPackagesAreInstalledThroughSudoOrAsRoot) {
  test::TempDir dir;
  const FakeDebian with_sudo(dir, "", 1000, true);
  EXPECT_EQ(with_sudo.run("bench").exit_code, 0);
  EXPECT_NE(with_sudo.calls().find("sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -q "
                                   "--no-install-recommends libbenchmark-dev"),
            std::string::npos)
      << with_sudo.calls();
  test::TempDir dir2;
  const FakeDebian root(dir2, "", 0, false);
  EXPECT_EQ(root.run("bench").exit_code, 0);
  EXPECT_NE(root.calls().find("apt-get install -y -q --no-install-recommends libbenchmark-dev"), std::string::npos)
      << root.calls();
  EXPECT_EQ(root.run("nonsense").exit_code, 2);
}

}  // namespace
}  // namespace cellbake

// The strategy generator with its simulation workers reached as a service
// (the simulation_worker plug-in's sim/simulate), one worker SIGKILLed
// mid-run each time; the library must be the one a generation with a local
// worker process writes.
// - In two host processes of the generator's own pipeline, over shared
//   memory; the killed host is started again by the kernel.
// - On "other machines": two worker kernels (one with two threads, one with
//   one) in a network namespace joined to this one by a veth pair, over
//   Cyclone DDS; the generator here, with no local workers and 3 remote
//   ones; the one-thread kernel is killed. Where namespaces are not
//   permitted the same runs on loopback, and says so.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <filesystem>
#include <iostream>
#include <regex>

#include "plr/sim/library.hpp"
#include "plr/sim/testing/library_fingerprint.hpp"
#include "remote_fixture.hpp"

namespace {

namespace fs = std::filesystem;
using namespace plr::remote_test;

// `workers`: lines of the generator's params; `tail`: more nodes, or a
// remote block.
std::string generator_config(const std::string& name, const std::string& workers,
                             const std::string& tail) {
  // Named per run: two pipelines of one name cannot run at once.
  return fmt::format("pipeline: {}_{}\n", name, ::getpid()) +
         "nodes:\n"
         "  generator:\n"
         "    plugin: strategy_generator\n"
         "    params:\n"
         "      library: ${report_dir}/library.plrl\n"
         "      checkpoint_dir: ${report_dir}/checkpoint\n"
         "      worlds: [{family: A1, world_file: " BLOCK_WORLD
         "}]\n"
         "      particles: 3\n"
         "      horizon: 3\n"
         "      trials: 6\n"
         "      progress: false\n"
         "      observation: {h_pile: 0.55, pile_mid: 0.25, pile_high: 0.4, wall_mid: 1.2, "
         "wall_high: 1.9}\n" +
         workers + tail;
}

// The library of a generation with one local worker process, made once.
const std::string& local_fingerprint(const std::string& dir) {
  static const std::string made = [&] {
    const auto local = write_file(dir + "local.yaml",
                                  generator_config("generate_local", "      workers: 1\n", ""));
    Proc run("", {kPlr, "run", local, "--report", dir + "local"}, dir + "local.log");
    if (run.wait(300s) != 0) return "error: " + slurp(run.log);
    return plr::sim::testing::library_fingerprint(dir + "local/library.plrl");
  }();
  return made;
}

// Results in a result store's folder.
std::size_t stored(const fs::path& results) {
  std::error_code ec;
  std::size_t n = 0;
  for (fs::directory_iterator it(results, ec), end; !ec && it != end; it.increment(ec)) ++n;
  return n;
}

std::string fresh_dir(const std::string& name) {
  const std::string dir = ::testing::TempDir() + fmt::format("{}_{}/", name, ::getpid());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(RemoteWorkers, WorkersInHostProcessesOneKilledEqualsALocalGeneration) {
  const std::string dir = fresh_dir("host_workers");
  const std::string expected = local_fingerprint(fresh_dir("local_generation"));
  ASSERT_EQ(expected.rfind("block\n", 0), 0u) << expected;
  const auto config =
      write_file(dir + "hosts.yaml",
                 generator_config("generate_hosts", "      workers: 0\n      remote_workers: 2\n",
                                  "  w1: {plugin: simulation_worker, host: w1}\n"
                                  "  w2: {plugin: simulation_worker, host: w2}\n"
                                  "hosts: {w1: {}, w2: {}}\n"
                                  // The block world's states are small: slots far below
                                  // JobFrame's 4 MiB bound keep /dev/shm's need small.
                                  "topics: {sim/simulate: {slot_size: 262144}}\n"));
  Proc gen("", {kPlr, "run", config, "--report", dir + "run"}, dir + "run.log");
  const fs::path results = dir + "run/checkpoint/block/results";
  ASSERT_TRUE(eventually(240s, [&] { return stored(results) >= 3 || ::kill(gen.pid, 0) != 0; }) &&
              ::kill(gen.pid, 0) == 0)
      << slurp(gen.log);
  // Host w1 (a child of plr run) is killed; the kernel starts it again.
  std::string pid;
  ASSERT_EQ(sh(fmt::format("pgrep -P {} -f -- '--host w1'", gen.pid), &pid), 0) << pid;
  ASSERT_EQ(::kill(std::stoi(pid), SIGKILL), 0);
  ASSERT_EQ(gen.wait(300s), 0) << slurp(gen.log);
  const std::string log = slurp(gen.log);
  std::cout << "host_workers: generator log:\n" << log;
  EXPECT_EQ(plr::sim::testing::library_fingerprint(dir + "run/library.plrl"), expected);
  EXPECT_NE(log.find("remote workers: "), std::string::npos) << log;
}

TEST(RemoteWorkers, AGenerationOverDdsWorkersOneKilledEqualsALocalOne) {
  VethNamespace net;
  if (net.isolated) {
    std::cout << "remote_workers: worker kernels in network namespace " << net.ns << " (veth "
              << net.veth << "), the generator here\n";
  } else {
    std::cout << "remote_workers: NOTE network namespaces are not permitted here (" << net.why_not
              << "); workers and generator on loopback instead\n";
  }
  const std::string dir = fresh_dir("remote_workers");
  const int domain = 150 + ::getpid() % 80;
  const std::string expected = local_fingerprint(fresh_dir("local_generation"));
  ASSERT_EQ(expected.rfind("block\n", 0), 0u) << expected;

  auto worker = [&](int n, int threads) {
    return write_file(
        dir + fmt::format("worker{}.yaml", n),
        fmt::format("pipeline: sim_worker{}_{}\nnodes:\n  worker:\n    plugin: simulation_worker\n"
                    "    params: {{threads: {}}}\nremote:\n  dds: {{domain: {}, interfaces: [{}], "
                    "export: [\"sim/simulate\"]}}\n",
                    n, ::getpid(), threads, domain, net.there));
  };
  const std::string ns = net.target();
  auto w1 = std::make_unique<Proc>(
      ns, std::vector<std::string>{kPlr, "run", worker(1, 1), "--report", dir + "w1"},
      dir + "worker1.log");
  Proc w2(ns, {kPlr, "run", worker(2, 2), "--report", dir + "w2"}, dir + "worker2.log");
  // Both serve before the generation starts (it would wait for them anyway).
  for (const Proc* w : {w1.get(), &w2})
    ASSERT_TRUE(eventually(30s, [&] {
      return slurp(w->log).find("running (1 nodes)") != std::string::npos;
    })) << slurp(w->log);

  const auto remote =
      write_file(dir + "remote.yaml",
                 generator_config("generate_dds", "      workers: 0\n      remote_workers: 3\n",
                                  fmt::format("remote:\n  dds: {{domain: {}, interfaces: [{}], "
                                              "import: [\"sim/simulate\"]}}\n",
                                              domain, net.here)));
  Proc gen("", {kPlr, "run", remote, "--report", dir + "remote"}, dir + "remote.log");
  // The one-thread kernel is killed once the first results are in.
  const fs::path results = dir + "remote/checkpoint/block/results";
  ASSERT_TRUE(eventually(240s, [&] { return stored(results) >= 3; })) << slurp(gen.log);
  ASSERT_EQ(::kill(w1->pid, SIGKILL), 0);
  w1.reset();
  ASSERT_EQ(gen.wait(300s), 0) << slurp(gen.log);
  const std::string log = slurp(gen.log);
  std::cout << "remote_workers: generator log:\n" << log;
  EXPECT_EQ(plr::sim::testing::library_fingerprint(dir + "remote/library.plrl"), expected);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(log, m, std::regex(R"(remote workers: (\d+) jobs answered)")))
      << log;
  EXPECT_GT(std::stoi(m[1]), 0);
  // The kill cost the calls in flight there, and they were issued again.
  EXPECT_NE(log.find(fmt::format("dds: kernel 'sim_worker1_{}@", ::getpid())), std::string::npos)
      << log;
}

}  // namespace

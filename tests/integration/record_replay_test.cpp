// Recordings end to end: `plr run --record` of the small unloading job, read
// by @mcap/core (the format's own TypeScript library, tests/js), holds every
// message the bus carried on each recorded topic; `plr replay` puts them on
// another pipeline's bus, and `plr monitor` sees the same counts there.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <thread>

namespace {

namespace fs = std::filesystem;

// Runs a shell command; its stdout, and its exit status in `status`.
std::string run(const std::string& command, int* status) {
  std::string out;
  FILE* p = ::popen(command.c_str(), "r");
  if (p == nullptr) return out;
  std::array<char, 4096> buffer;
  for (std::size_t n; (n = std::fread(buffer.data(), 1, buffer.size(), p)) > 0;)
    out.append(buffer.data(), n);
  *status = ::pclose(p);
  return out;
}

fs::path make_dir() {
  std::string pattern = (fs::temp_directory_path() / "plr_record_XXXXXX").string();
  return ::mkdtemp(pattern.data());
}

TEST(Recording, HoldsEveryMessageAndReplaysWithTheSameCounts) {
  const fs::path dir = make_dir();
  const auto recording = dir / "run.mcap";
  const std::string tag = std::to_string(::getpid());
  int status = 0;
  run(std::string(PLR_BIN) + " run " + UNLOAD_SMALL_CONFIG + " --record " + recording.string() +
          " --report " + (dir / "report").string() + " --set pipeline=record_" + tag + " 2>" +
          (dir / "run.txt").string(),
      &status);
  ASSERT_EQ(status, 0) << std::ifstream(dir / "run.txt").rdbuf();
  ASSERT_TRUE(fs::exists(recording));
  const auto report = nlohmann::json::parse(std::ifstream(dir / "report" / "report.json"));
  const auto& carried = report.at("run").at("topic_messages");

  const auto read = nlohmann::json::parse(
      run(std::string(NODE) + " " + MCAP_CHECK + " " + recording.string(), &status), nullptr,
      false);
  ASSERT_EQ(status, 0);
  ASSERT_TRUE(read.is_object());
  // Every topic of the run with an SDK schema is there, whole, read both ways.
  for (const char* topic : {"world", "progress", "clock", "executor/state", "executor/status",
                            "kernel/telemetry", "pipeline/done"}) {
    ASSERT_TRUE(carried.contains(topic)) << topic << " " << carried.dump();
    EXPECT_GT(carried[topic].get<int>(), 0) << topic;
    EXPECT_EQ(read["stream"].value(topic, -1), carried[topic].get<int>()) << topic;
    EXPECT_EQ(read["indexed"].value(topic, -1), carried[topic].get<int>()) << topic;
  }
  int total = 0;
  for (const auto& [topic, n] : read["stream"].items()) total += n.get<int>();
  EXPECT_EQ(read["statistics"]["messageCount"], total);
  for (const auto& e : read["encodings"]) {
    EXPECT_EQ(e[1], "flatbuffer") << e.dump();
    EXPECT_EQ(e[3], "flatbuffer") << e.dump();
    EXPECT_GT(e[4].get<int>(), 0) << "schema bytes " << e.dump();
  }

  // Replayed, as fast as possible, into a pipeline that only listens, on a
  // DDS domain of this test's own (away from the other tests' 100..214, 225..232).
  const int domain = 215 + ::getpid() % 10;
  const auto config = dir / "replay.yaml";
  std::ofstream(config) << "pipeline: replay_" << tag << "\n"
                        << "remote: {dds: {domain: " << domain << "}}\n"
                        << "nodes:\n  doubler: {plugin: demo_doubler}\n";
  const std::string replay = std::string(PLR_BIN) + " replay " + recording.string() + " " +
                             config.string() + " --speed 0 --linger 20 --report " +
                             (dir / "replay").string() + " 2>" + (dir / "replay.txt").string();
  std::thread replaying([&] {
    int s = 0;
    run(replay, &s);
    EXPECT_EQ(s, 0) << std::ifstream(dir / "replay.txt").rdbuf();
  });
  // `plr monitor` until the replaying kernel's telemetry shows every message.
  std::map<std::string, int> seen;
  bool same = false;
  for (int i = 0; i < 15 && !same; ++i) {
    const auto doc = nlohmann::json::parse(
        run(std::string(PLR_BIN) + " monitor --once --json --wait 5 --domain " +
                std::to_string(domain) + " 2>/dev/null",
            &status),
        nullptr, false);
    seen.clear();
    if (doc.is_object())
      for (const auto& k : doc["kernels"])
        if (k.value("kernel", "").rfind("replay_" + tag + "@", 0) == 0)
          for (const auto& t : k["telemetry"]["topics"])
            seen[t.value("name", "")] = t.value("messages", 0);
    same = !seen.empty();
    for (const auto& [topic, n] : read["stream"].items())
      if (topic != "kernel/telemetry" && seen[topic] != n.get<int>()) same = false;
    if (!same) std::this_thread::sleep_for(std::chrono::seconds(1));
  }
  replaying.join();
  for (const auto& [topic, n] : read["stream"].items()) {
    if (topic == "kernel/telemetry") continue;  // the replaying kernel publishes its own too
    EXPECT_EQ(seen[topic], n.get<int>()) << topic;
  }
  fs::remove_all(dir);
}

}  // namespace

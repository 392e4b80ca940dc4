#include "plr/jobs/slurm_runner.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <plr/atomic_file.hpp>
#include <plr/frame.hpp>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <thread>

#include "plr/jobs/messages.hpp"

namespace plr::jobs {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Slurm refuses arrays past MaxArraySize (1001 by default): indices 0..999.
constexpr std::size_t kMaxArray = 1000;
constexpr std::size_t kMaxBatchBytes = std::size_t{1} << 30;

std::string shell_quoted(const std::string& s) {
  std::string q = "'";
  for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Runs `command` with sh; its exit code, and stdout and stderr in `out`.
int shell(const std::string& command, std::string& out) {
  out.clear();
  FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  const int status = ::pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

bool active(const std::string& state) {
  static const std::set<std::string> kActive = {
      "PENDING",  "RUNNING",   "CONFIGURING", "COMPLETING",   "SUSPENDED",  "REQUEUED",
      "RESIZING", "SIGNALING", "STAGE_OUT",   "REQUEUE_HOLD", "REQUEUE_FED"};
  return kActive.count(state) > 0;
}

struct Task {
  std::string array;  // Slurm's job id of the array
  std::size_t index = 0;
};

}  // namespace

nlohmann::json to_json(const SlurmStats& s) {
  return {{"kind", "slurm"},
          {"arrays", s.arrays},
          {"tasks", s.tasks},
          {"resubmitted", s.resubmitted},
          {"ended_without_result", s.ended_without_result},
          {"submit_to_first_running_s", s.first_running_s},
          {"wall_s", s.wall_s}};
}

void SlurmRunner::run(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                      const Done& done, const std::function<bool()>& stop) {
  const Clock::time_point t0 = Clock::now();
  const fs::path batches = store_.dir() / "batches";
  std::error_code ec;
  fs::create_directories(batches, ec);
  // Batches are numbered on from the highest left by an earlier run.
  std::size_t batch_number = 0;
  for (const auto& entry : fs::directory_iterator(batches, ec)) {
    const std::string stem = entry.path().stem().string();
    if (!stem.empty() && stem.find_first_not_of("0123456789") == std::string::npos)
      batch_number = std::max<std::size_t>(batch_number, std::stoull(stem) + 1);
  }
  std::vector<fs::path> written_files;

  std::map<std::size_t, Task> task_of;           // job -> its latest array task
  std::map<std::size_t, unsigned> attempts;      // job -> submissions
  std::map<std::size_t, unsigned> absent_polls;  // job -> polls seen ended without a result
  std::vector<std::string> arrays;
  std::set<std::size_t> pending(todo.begin(), todo.end());

  auto fail = [&](std::size_t i, std::string why) {
    Result r;
    r.key = jobs[i].key;
    r.error = std::move(why);
    r.attempts = attempts[i];
    pending.erase(i);
    done(i, std::move(r));
  };

  // Writes `chosen` as batch files and submits them; a job that cannot be
  // submitted fails with sbatch's words.
  auto submit = [&](const std::vector<std::size_t>& chosen) {
    for (std::size_t from = 0; from < chosen.size(); from += kMaxArray) {
      const std::size_t n = std::min(kMaxArray, chosen.size() - from);
      const std::string name = fmt::format("{:06}", batch_number++);
      Bytes bytes;
      for (std::size_t k = 0; k < n; ++k) {
        const Bytes request = encode_request(k, jobs[chosen[from + k]]);
        const Bytes framed = plr::frame(request.data(), request.size());
        bytes.insert(bytes.end(), framed.begin(), framed.end());
      }
      const fs::path batch = batches / (name + ".batch"), script = batches / (name + ".sh");
      std::string command = "exec";
      for (const auto& word : command_) command += " " + shell_quoted(word);
      command += " " + shell_quoted(batch.string());
      auto written = plr::write_file_atomically(
          batch.string(),
          std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
      if (written)
        written = plr::write_file_atomically(script.string(), "#!/bin/sh\n" + command + "\n");
      written_files.insert(written_files.end(), {batch, script});
      std::string out;
      std::string sbatch = fmt::format(
          "sbatch --parsable --job-name={} --array=0-{}{} --output={}",
          shell_quoted(options_.job_name), n - 1,
          options_.max_parallel ? fmt::format("%{}", options_.max_parallel) : std::string(),
          shell_quoted((store_.logs() / "slurm-%A_%a.out").string()));
      if (!options_.partition.empty()) sbatch += " --partition=" + shell_quoted(options_.partition);
      if (!options_.account.empty()) sbatch += " --account=" + shell_quoted(options_.account);
      if (!options_.time_limit.empty()) sbatch += " --time=" + shell_quoted(options_.time_limit);
      for (const auto& arg : options_.sbatch_args) sbatch += " " + shell_quoted(arg);
      sbatch += " " + shell_quoted(script.string());
      const int rc = written ? shell(sbatch, out) : -1;
      // --parsable prints "jobid" or "jobid;cluster".
      const std::string id = out.substr(0, out.find_first_of(";\n"));
      const bool ok =
          rc == 0 && !id.empty() && id.find_first_not_of("0123456789") == std::string::npos;
      for (std::size_t k = 0; k < n; ++k) {
        const std::size_t i = chosen[from + k];
        ++attempts[i];
        if (!ok) {
          fail(i, written ? fmt::format("sbatch failed ({}): {}", rc, out.substr(0, out.find('\n')))
                          : written.error().message);
          continue;
        }
        task_of[i] = {id, k};
        absent_polls[i] = 0;
      }
      if (ok) {
        arrays.push_back(id);
        ++stats_.arrays;
        stats_.tasks += n;
      }
    }
  };

  auto cancel = [&] {
    if (arrays.empty()) return;
    std::string ids, out;
    for (const auto& id : arrays) ids += (ids.empty() ? "" : ",") + id;
    shell("scancel " + ids, out);
  };

  submit({todo.begin(), todo.end()});
  while (!pending.empty()) {
    for (double waited = 0; waited < options_.poll_s && !stop(); waited += 0.05)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (stop()) {
      cancel();
      break;
    }
    auto report = [&](std::size_t i) {
      auto stored = store_.load(jobs[i].key);
      if (!stored) return false;
      stored->stored = false;
      stored->attempts = attempts[i];
      if (stats_.first_running_s < 0)
        stats_.first_running_s = std::chrono::duration<double>(Clock::now() - t0).count();
      pending.erase(i);
      done(i, std::move(*stored));
      return true;
    };
    for (const std::size_t i : std::vector<std::size_t>(pending.begin(), pending.end())) report(i);
    if (pending.empty()) break;

    std::set<std::string> live;
    for (const std::size_t i : pending) live.insert(task_of[i].array);
    std::string ids, out;
    for (const auto& id : live) ids += (ids.empty() ? "" : ",") + id;
    // squeue refuses ids the controller has forgotten: those tasks are gone.
    if (shell("squeue -h -r -t all -o '%i %T' -j " + ids, out) != 0 &&
        out.find("Invalid job id") == std::string::npos)
      continue;                                // the controller is busy: look again
    std::map<std::string, std::string> state;  // "array_index" -> state
    std::istringstream lines(out);
    for (std::string task, s; lines >> task >> s;) state[task] = s;

    std::vector<std::size_t> again;
    for (const std::size_t i : std::vector<std::size_t>(pending.begin(), pending.end())) {
      const Task& t = task_of[i];
      const auto it = state.find(fmt::format("{}_{}", t.array, t.index));
      const std::string s = it == state.end() ? "GONE" : it->second;
      if (s == "RUNNING" && stats_.first_running_s < 0)
        stats_.first_running_s = std::chrono::duration<double>(Clock::now() - t0).count();
      if (active(s)) continue;
      // Ended: its result may reach this filesystem a moment after the task.
      if (report(i) || ++absent_polls[i] < 2) continue;
      ++stats_.ended_without_result[s];
      if (attempts[i] < options_.max_attempts) {
        again.push_back(i);
        continue;
      }
      fail(i, fmt::format(
                  "Slurm task {}_{} ended {} without a result, {} attempts; log: {}", t.array,
                  t.index, s, attempts[i],
                  (store_.logs() / fmt::format("slurm-{}_{}.out", t.array, t.index)).string()));
    }
    if (!again.empty()) {
      stats_.resubmitted += again.size();
      submit(again);
    }
  }
  // Every job has its result or has failed: the batches are not read
  // again (a stopped run keeps them for the tasks the scheduler may still
  // be ending).
  if (pending.empty())
    for (const fs::path& f : written_files) fs::remove(f, ec);
  stats_.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
}

int run_array_task(const Kinds& kinds, const fs::path& batch_file,
                   const std::function<void()>& prepare) {
  const char* id = std::getenv("SLURM_ARRAY_TASK_ID");
  char* end = nullptr;
  const unsigned long index = id ? std::strtoul(id, &end, 10) : 0;
  if (!id || *end != '\0') {
    std::fprintf(stderr, "plr job task: SLURM_ARRAY_TASK_ID is not set to a number\n");
    return 2;
  }
  std::error_code ec;
  const auto size = fs::file_size(batch_file, ec);
  if (ec || size > kMaxBatchBytes) {
    std::fprintf(stderr, "plr job task: %s: %s\n", batch_file.c_str(),
                 ec ? ec.message().c_str() : "larger than 1 GiB");
    return 2;
  }
  std::ifstream in(batch_file, std::ios::binary);
  const Bytes bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  plr::FrameReader reader(kMaxBytes + 4096, batch_file.string());
  reader.feed(bytes.data(), bytes.size());
  std::optional<Job> job;
  for (unsigned long k = 0; k <= index; ++k) {
    auto frame = reader.next();
    if (!frame || !*frame) {
      std::fprintf(stderr, "plr job task: %s has no job %lu%s\n", batch_file.c_str(), index,
                   frame ? "" : (": " + frame.error().message).c_str());
      return 2;
    }
    if (k < index) continue;
    auto message = decode_message((*frame)->data(), (*frame)->size(), batch_file.string());
    if (!message || message->type != Message::Type::kRequest) {
      std::fprintf(stderr, "plr job task: %s\n",
                   message ? "a batch holds a reply" : message.error().message.c_str());
      return 2;
    }
    job = std::move(message->job);
  }
  auto store = Store::open(batch_file.parent_path().parent_path());
  if (!store) {
    std::fprintf(stderr, "plr job task: %s\n", store.error().message.c_str());
    return 2;
  }
  if (store->load(job->key)) return 0;  // a finished job is not run again
  const int log =
      ::open(store->log_file(job->key).c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log >= 0) ::dup2(log, STDERR_FILENO);
  if (prepare) prepare();
  const Result result = kinds.run(*job);
  if (!result.ok)
    std::fprintf(stderr, "job %s failed: %s\n", job->key.c_str(), result.error.c_str());
  if (auto saved = store->save(result); !saved) {
    std::fprintf(stderr, "plr job task: %s\n", saved.error().message.c_str());
    return 1;
  }
  return 0;
}

}  // namespace plr::jobs

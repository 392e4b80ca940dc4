#include "training/rollout.hpp"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <plr/msg/generator_generated.h>

#include <fmt/format.h>

#include <cerrno>
#include <csignal>
#include <cstring>

#include "plr/actions/state_bytes.hpp"
#include "plr/episode/open_loop.hpp"

namespace plr::chooser {

namespace {

// A child's answer on its pipe: ok flag, actions, boxes, robot seconds,
// then the end state's bytes or the error's text.
struct Header {
  std::uint32_t ok = 0;
  std::uint32_t boxes = 0;
  std::uint64_t actions = 0;
  double robot_time_s = 0.0;
  std::uint64_t payload = 0;
};

bool write_all(int fd, const void* data, std::size_t size) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

bool read_all(int fd, void* data, std::size_t size) {
  auto* p = static_cast<std::uint8_t*>(data);
  while (size > 0) {
    const ssize_t n = ::read(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

constexpr std::uint64_t kMaxPayload = std::uint64_t{1} << 30;

}  // namespace

plr::Expected<std::unique_ptr<Rig>> Rig::create(const sim::ObservationParams& observation) {
  actions::ActionOptions options;
  options.observation = observation;
  auto rig = actions::Rig::create(std::move(options));
  if (!rig) return rig.error();
  return std::unique_ptr<Rig>(new Rig(std::move(*rig)));
}

std::vector<std::uint8_t> Rig::snapshot(const actions::Memory& memory) const {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(actions::build(fbb, actions::SimState{rig_->simulation().save(), memory}));
  return {fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()};
}

std::vector<std::uint8_t> Rig::start(const sim::World& truth) {
  rig_->reset(truth);
  return snapshot({});
}

plr::Expected<actions::Memory> Rig::restore(const std::vector<std::uint8_t>& state) {
  flatbuffers::Verifier verifier(state.data(), state.size());
  if (!verifier.VerifyBuffer<plr::msg::TruckState>(nullptr))
    return plr::make_error(PLR_ERR_INVALID, "state: not a TruckState");
  auto s =
      actions::from_message(*flatbuffers::GetRoot<plr::msg::TruckState>(state.data()), "state");
  if (!s) return s.error();
  rig_->simulation().restore(*s->saved);
  return std::move(s->memory);
}

plr::Expected<actions::Perceived> Rig::observe(const std::vector<std::uint8_t>& state) {
  auto memory = restore(state);
  if (!memory) return memory.error();
  return rig_->backend().observe();
}

plr::Expected<Rollout> Rig::run(const std::vector<std::uint8_t>& state, const Job& job,
                                const sim::HardcodedParams& h, std::uint64_t max_actions) {
  auto memory = restore(state);
  if (!memory) return memory.error();
  if (!job.masses.empty())
    if (auto ok = rig_->simulation().set_masses(job.masses); !ok) return ok.error();
  auto run =
      episode::run_open_loop(rig_->model(), rig_->backend(), *memory, job.strategy, h, max_actions);
  if (!run) return run.error();
  return Rollout{run->actions, run->boxes, run->robot_time_s, snapshot(*memory)};
}

std::vector<plr::Expected<Rollout>> Rig::run_parallel(const std::vector<std::uint8_t>& state,
                                                      const std::vector<Job>& jobs,
                                                      const sim::HardcodedParams& h,
                                                      std::uint64_t max_actions, int workers) {
  std::vector<plr::Expected<Rollout>> results(jobs.size(),
                                              plr::make_error(PLR_ERR_INTERNAL, "rollout not run"));
  struct Child {
    pid_t pid;
    int fd;
    std::size_t job;
  };
  std::size_t next = 0;
  while (next < jobs.size()) {
    std::vector<Child> children;
    for (; next < jobs.size() && children.size() < static_cast<std::size_t>(workers); ++next) {
      int fds[2];
      if (::pipe2(fds, O_CLOEXEC) != 0) {
        results[next] =
            plr::make_error(PLR_ERR_INTERNAL, std::string("pipe: ") + std::strerror(errno));
        continue;
      }
      const pid_t parent = ::getpid();
      const pid_t pid = ::fork();
      if (pid == 0) {
        // A rollout outlives no killed training: it would only hold a core.
        if (::prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || ::getppid() != parent) std::_Exit(1);
        ::close(fds[0]);
        auto r = run(state, jobs[next], h, max_actions);
        Header head;
        std::string text;
        const std::uint8_t* payload = nullptr;
        if (r) {
          head = {1, r->boxes, r->actions, r->robot_time_s, r->end.size()};
          payload = r->end.data();
        } else {
          text = r.error().message;
          head.payload = text.size();
          payload = reinterpret_cast<const std::uint8_t*>(text.data());
        }
        const bool sent = write_all(fds[1], &head, sizeof head) &&
                          write_all(fds[1], payload, static_cast<std::size_t>(head.payload));
        std::_Exit(sent ? 0 : 1);
      }
      ::close(fds[1]);
      if (pid < 0) {
        ::close(fds[0]);
        results[next] =
            plr::make_error(PLR_ERR_INTERNAL, std::string("fork: ") + std::strerror(errno));
        continue;
      }
      children.push_back({pid, fds[0], next});
    }
    // A child blocked on a full pipe waits for its turn here; the others
    // run on meanwhile.
    for (const Child& c : children) {
      Header head;
      std::vector<std::uint8_t> payload;
      bool got = read_all(c.fd, &head, sizeof head) && head.payload <= kMaxPayload;
      if (got) {
        payload.resize(static_cast<std::size_t>(head.payload));
        got = read_all(c.fd, payload.data(), payload.size());
      }
      ::close(c.fd);
      int status = 0;
      while (::waitpid(c.pid, &status, 0) < 0 && errno == EINTR) {
      }
      if (!got) {
        results[c.job] = plr::make_error(
            PLR_ERR_INTERNAL,
            WIFSIGNALED(status) ? fmt::format("rollout process died (signal {})", WTERMSIG(status))
                                : std::string("rollout process ended without an answer"));
      } else if (head.ok == 1) {
        results[c.job] = Rollout{head.actions, head.boxes, head.robot_time_s, std::move(payload)};
      } else {
        results[c.job] =
            plr::make_error(PLR_ERR_INVALID, std::string(payload.begin(), payload.end()));
      }
    }
  }
  return results;
}

}  // namespace plr::chooser

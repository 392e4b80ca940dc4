// A single-node Slurm cluster for tests, from Debian's packages: munged,
// slurmctld and slurmd run in the foreground as children of the test, with a
// generated munge key and slurm.conf in a temporary folder (linuxproc process
// tracking, no cgroups, no accounting database). The client commands (sbatch,
// squeue, scancel, scontrol) find it through SLURM_CONF, set in this process's
// environment while the cluster lives. Needs root (the daemons run as root);
// `start()` says why when it cannot start.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "remote_fixture.hpp"

extern char** environ;

namespace plr::slurm_test {

class SlurmCluster {
 public:
  SlurmCluster() = default;
  SlurmCluster(const SlurmCluster&) = delete;
  SlurmCluster& operator=(const SlurmCluster&) = delete;
  ~SlurmCluster() { stop(); }

  // Starts the daemons and waits until the node takes jobs. Empty on success,
  // otherwise why the cluster cannot run here.
  std::string start() {
    if (::geteuid() != 0) return "needs root to run slurmctld and slurmd";
    for (const char* program : {"/usr/sbin/munged", "/usr/sbin/slurmctld", "/usr/sbin/slurmd"})
      if (!std::filesystem::exists(program))
        return std::string(program) + " is not installed (scripts/setup.sh installs it)";
    dir_ = std::filesystem::temp_directory_path() /
           ("plr-slurm-" + std::to_string(::getpid()) + "-" + std::to_string(random_port()));
    std::filesystem::create_directories(dir_ / "munge");
    std::filesystem::create_directories(dir_ / "state");
    std::filesystem::create_directories(dir_ / "spool");
    std::filesystem::permissions(dir_ / "munge", std::filesystem::perms::owner_all);
    if (!write_key() || !write_conf())
      return "cannot write the cluster's files in " + dir_.string();
    ::setenv("SLURM_CONF", conf().c_str(), 1);

    const std::string munge = (dir_ / "munge").string();
    if (!spawn({"/usr/sbin/munged", "-F", "--force", "--key-file=" + munge + "/munge.key",
                "--socket=" + munge + "/munge.socket", "--pid-file=" + munge + "/munged.pid",
                "--log-file=" + munge + "/munged.log", "--seed-file=" + munge + "/seed"}))
      return "munged did not start";
    for (int i = 0; i < 100 && !std::filesystem::exists(munge + "/munge.socket"); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (!spawn({"/usr/sbin/slurmctld", "-D", "-i", "-f", conf()}) ||
        !spawn({"/usr/sbin/slurmd", "-D", "-f", conf()}))
      return "slurmctld or slurmd did not start";
    for (int i = 0; i < 200; ++i) {
      std::string out;
      if (run("sinfo -h -o %t", &out) == 0 && out.find("idle") != std::string::npos) return {};
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return "the node did not become idle within 20 s (logs in " + dir_.string() + ")";
  }

  void stop() {
    if (!pids_.empty()) {  // the jobs first, so no slurmstepd outlives its slurmd
      run("scancel --full --user=root");
      for (int i = 0; i < 50 && !queue().empty(); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    for (auto it = pids_.rbegin(); it != pids_.rend(); ++it) ::kill(*it, SIGTERM);
    for (const pid_t pid : pids_) {
      int status = 0;
      for (int i = 0; i < 100 && ::waitpid(pid, &status, WNOHANG) == 0; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (::waitpid(pid, &status, WNOHANG) == 0) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
      }
    }
    pids_.clear();
    if (!dir_.empty()) {
      ::unsetenv("SLURM_CONF");
      std::error_code ec;
      std::filesystem::remove_all(dir_, ec);
      dir_.clear();
    }
  }

  std::string conf() const { return (dir_ / "slurm.conf").string(); }
  const std::filesystem::path& dir() const { return dir_; }

  // Runs a shell command (sbatch, squeue, ...) against this cluster.
  static int run(const std::string& command, std::string* out = nullptr) {
    return plr::remote_test::sh(command, out);
  }

  // The array tasks still queued or running, one "jobid_task STATE" per line.
  static std::string queue() {
    std::string out;
    run("squeue -h -r -o '%i %T'", &out);
    return out;
  }

 private:
  static int random_port() {
    std::random_device device;
    return 20000 + static_cast<int>(device() % 20000);
  }

  bool write_key() const {
    std::ofstream key(dir_ / "munge" / "munge.key", std::ios::binary);
    std::random_device device;
    for (int i = 0; i < 1024; ++i) key.put(static_cast<char>(device() & 0xff));
    key.close();
    std::filesystem::permissions(
        dir_ / "munge" / "munge.key",
        std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
    return static_cast<bool>(key);
  }

  bool write_conf() const {
    char host[256] = {};
    ::gethostname(host, sizeof host - 1);
    std::string name = host;
    name = name.substr(0, name.find('.'));
    const int port = random_port();
    const std::string d = dir_.string();
    std::ofstream c(conf());
    c << "ClusterName=plrtest\nSlurmctldHost=" << name << "\nSlurmUser=root\nSlurmdUser=root\n"
      << "AuthType=auth/munge\nCredType=cred/munge\nAuthInfo=socket=" << d
      << "/munge/munge.socket\n"
      << "SlurmctldPort=" << port << "\nSlurmdPort=" << port + 1 << "\n"
      << "StateSaveLocation=" << d << "/state\nSlurmdSpoolDir=" << d << "/spool\n"
      << "SlurmctldPidFile=" << d << "/slurmctld.pid\nSlurmdPidFile=" << d << "/slurmd.pid\n"
      << "SlurmctldLogFile=" << d << "/slurmctld.log\nSlurmdLogFile=" << d << "/slurmd.log\n"
      << "ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n"
      << "JobAcctGatherType=jobacct_gather/none\nAccountingStorageType=accounting_storage/none\n"
      << "JobCompType=jobcomp/none\nSchedulerType=sched/backfill\n"
      << "SelectType=select/cons_tres\nSelectTypeParameters=CR_CPU\n"
      << "ReturnToService=2\nMpiDefault=none\nSwitchType=switch/none\nMinJobAge=600\n"
      << "NodeName=" << name << " CPUs=" << std::thread::hardware_concurrency()
      << " State=UNKNOWN\nPartitionName=test Nodes=" << name
      << " Default=YES MaxTime=INFINITE State=UP\n";
    return static_cast<bool>(c);
  }

  bool spawn(const std::vector<std::string>& argv) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    ::posix_spawn_file_actions_init(&actions);
    const std::string log =
        (dir_ / (std::filesystem::path(argv[0]).filename().string() + ".out")).string();
    ::posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                       0600);
    ::posix_spawn_file_actions_adddup2(&actions, 1, 2);
    pid_t pid = 0;
    const int rc = ::posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
    ::posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) return false;
    pids_.push_back(pid);
    return true;
  }

  std::filesystem::path dir_;
  std::vector<pid_t> pids_;
};

}  // namespace plr::slurm_test

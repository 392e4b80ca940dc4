#include "plr/jobs/signals.hpp"

#include <csignal>

namespace plr::jobs {

namespace {

volatile std::sig_atomic_t g_signal = 0;

void on_signal(int signal) {
  g_signal = signal;
}

}  // namespace

StopOnSignals::StopOnSignals() {
  g_signal = 0;
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, &old_int_);
  ::sigaction(SIGTERM, &action, &old_term_);
}

StopOnSignals::~StopOnSignals() {
  ::sigaction(SIGINT, &old_int_, nullptr);
  ::sigaction(SIGTERM, &old_term_, nullptr);
}

bool StopOnSignals::operator()() const {
  return g_signal != 0;
}

int StopOnSignals::signal() const {
  return g_signal;
}

}  // namespace plr::jobs

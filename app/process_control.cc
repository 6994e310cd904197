#include "app/process_control.h"

#include <fmt/format.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

#include "base/error.h"
#include "base/subprocess.h"

namespace ms::app {
namespace {

std::atomic<int> g_stop_signal{0};

void OnStopSignal(int sig) {
  // A second Ctrl-C kills at once. Repeated SIGTERMs do not: batch systems send one to every
  // process of a job and scripts often forward another.
  if (g_stop_signal.exchange(sig) != 0 && sig == SIGINT) {
    ::signal(sig, SIG_DFL);
    ::raise(sig);
  }
}

}  // namespace

void InstallStopSignals() {
  struct sigaction action;
  std::memset(&action, 0, sizeof(action));
  action.sa_handler = &OnStopSignal;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, nullptr);
  ::sigaction(SIGTERM, &action, nullptr);
  ::signal(SIGPIPE, SIG_IGN);
}

bool StopRequested() { return g_stop_signal.load() != 0; }
int StopSignal() { return g_stop_signal.load(); }

pid_t SpawnSelf(const std::vector<std::string>& args) {
  SubprocessOptions child;
  child.executable = "/proc/self/exe";
  child.argv = {"manisweep"};
  child.argv.insert(child.argv.end(), args.begin(), args.end());
  return StartSubprocess(child);
}

int StopChildren(const std::vector<pid_t>& pids, double grace_s) {
  std::vector<pid_t> alive = pids;
  auto reap = [&](double wait_s) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
    while (!alive.empty()) {
      for (auto it = alive.begin(); it != alive.end();) {
        int status = 0;
        const pid_t r = ::waitpid(*it, &status, WNOHANG);
        it = (r == *it || (r < 0 && errno == ECHILD)) ? alive.erase(it) : it + 1;
      }
      if (alive.empty() || std::chrono::steady_clock::now() >= deadline) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  };
  reap(grace_s);
  int signalled = 0;
  for (int sig : {SIGTERM, SIGKILL}) {
    if (alive.empty()) break;
    for (pid_t pid : alive) ::kill(pid, sig);
    signalled += static_cast<int>(alive.size());
    reap(sig == SIGTERM ? grace_s : 5.0);
  }
  return signalled;
}

}  // namespace ms::app

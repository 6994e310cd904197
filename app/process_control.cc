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

std::string Describe(int status) {
  if (WIFEXITED(status)) return fmt::format("exit code {}", WEXITSTATUS(status));
  if (WIFSIGNALED(status)) {
    return fmt::format("killed by signal {} ({})", WTERMSIG(status), strsignal(WTERMSIG(status)));
  }
  return "stopped";
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
  // Everything the child needs is prepared before fork: between fork and exec only
  // async-signal-safe calls.
  std::vector<std::string> storage = {"manisweep"};
  storage.insert(storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& s : storage) argv.push_back(s.data());
  argv.push_back(nullptr);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) throw InternalError(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(1);  // the parent died before prctl
    // The parent ignores nothing the child should: restore default signal actions.
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    ::signal(SIGPIPE, SIG_DFL);
    ::execv("/proc/self/exe", argv.data());
    ::_exit(127);
  }
  return pid;
}

bool ReapIfExited(pid_t pid, std::string* how) {
  int status = 0;
  const pid_t r = ::waitpid(pid, &status, WNOHANG);
  if (r != pid) return false;
  *how = Describe(status);
  return true;
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

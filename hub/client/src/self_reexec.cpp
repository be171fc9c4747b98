// Re-executing this process (see self_reexec.hpp).
#include "self_reexec.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/header.hpp"
#include "hub_loss_state.hpp"

namespace afhub::hub_loss {
namespace {

// Those install_stop_signal_handlers() handles (rt/stop_signal.cpp).
constexpr int kStopSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};

std::vector<std::string> own_arguments() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::vector<std::string> arguments;
  std::string argument;
  while (std::getline(in, argument, '\0')) arguments.push_back(argument);
  if (arguments.empty())
    throw Error(
        "cannot read this process's arguments from /proc/self/cmdline: it could not "
        "re-attach to a hub that comes back");
  return arguments;
}

}  // namespace

void prepare_self_reexec() {
  State& s = state();
  s.arguments = own_arguments();
  for (char** entry = environ; *entry; ++entry) s.environment.emplace_back(*entry);
  for (std::string& argument : s.arguments) s.argv.push_back(argument.data());
  s.argv.push_back(nullptr);
  for (std::string& entry : s.environment) s.envp.push_back(entry.data());
  s.envp.push_back(s.reattach_entry);
  s.envp.push_back(nullptr);
  pthread_sigmask(SIG_SETMASK, nullptr, &s.signal_mask);
}

void reexecute_self() noexcept {
  State& s = state();
  std::snprintf(s.reattach_entry, sizeof s.reattach_entry, "%s=%u:%llu:%lld:%lld",
                kReattachVariable, s.reattach_count + 1,
                static_cast<unsigned long long>(s.attached_hub.load()),
                static_cast<long long>(monotonic_ns()), static_cast<long long>(s.carried.load()));
  std::fflush(stdout);
  std::fflush(stderr);
  // Only the three standard streams go across: iceoryx's descriptors (its runtime
  // name's lock file among them) would otherwise keep their locks in the new image.
  if (close_range(3, ~0U, CLOSE_RANGE_CLOEXEC) != 0)
    for (int fd = 3; fd < 65536; ++fd) fcntl(fd, F_SETFD, FD_CLOEXEC);
  sigset_t mask = s.signal_mask;
  for (const int signal : kStopSignals) sigaddset(&mask, signal);
  pthread_sigmask(SIG_SETMASK, &mask, nullptr);
  // One another thread took since the caller looked would be lost with this image;
  // one it takes from now on comes to this thread too, held for the new image.
  forward_stop_signals_to_this_thread();
  if (stop_requested()) _exit(0);
  execve("/proc/self/exe", s.argv.data(), s.envp.data());
  std::fprintf(stderr, "%s: cannot re-execute itself to re-attach: %s\n", s.who.c_str(),
               std::strerror(errno));
  _exit(1);
}

void unblock_stop_signals() noexcept {
  sigset_t stop;
  sigemptyset(&stop);
  for (const int signal : kStopSignals) sigaddset(&stop, signal);
  pthread_sigmask(SIG_UNBLOCK, &stop, nullptr);
}

}  // namespace afhub::hub_loss

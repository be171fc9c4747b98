// The stop flag (see stop_signal.hpp).
#include "afhub/hub/stop_signal.hpp"

#include <signal.h>

#include <atomic>

namespace afhub {
namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int) {
  g_stop = true;
}
}  // namespace

void install_stop_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool stop_requested() {
  return g_stop;
}

}  // namespace afhub

// SIGINT and SIGTERM for long-running processes: a flag their loops poll.
#pragma once

namespace afhub {

void install_stop_signal_handlers();
bool stop_requested();

}  // namespace afhub

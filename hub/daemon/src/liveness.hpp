// Whether a process or thread still runs, by its id: the hub's one liveness rule.
// A process stopped in a debugger or by SIGSTOP still runs; a killed one does not.
#pragma once

#include <sys/types.h>

namespace afhub {

// True when `id` (a pid or a thread id) has no /proc entry, or is a zombie (its
// parent has not reaped it yet, but it will never run again).
bool task_is_gone(pid_t id);

}  // namespace afhub

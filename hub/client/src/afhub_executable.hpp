// The afhub executable that starts a hub for a process that found none.
#pragma once

#include <string>

namespace afhub {

// $AFHUB_EXECUTABLE, else an `afhub` beside this program, else the first on $PATH.
// Throws afhub::Error saying what to do when there is none.
std::string afhub_executable();

}  // namespace afhub

// RouDi with afhub's liveness rule: a registered process is alive while its pid
// exists. iceoryx's own rule (a keep-alive every 300 ms, dropped after 1.5 s of
// silence) kills a process that was merely stopped: a debugger breakpoint, Ctrl-Z,
// a VM pause. So RouDi runs with its monitoring off, and the hub removes a process
// only once it is gone (liveness.hpp), as RouDi would have: its ports and chunks
// are freed.
#pragma once

#include <string>

#include "iceoryx_posh/internal/roudi/roudi.hpp"

namespace afhub {

class AfhubRouDi : public iox::roudi::RouDi {
 public:
  AfhubRouDi(iox::roudi::RouDiMemoryInterface& memory, iox::roudi::PortManager& ports);
  ~AfhubRouDi() override;

  // Unregisters the process `name`: its ports, its chunks. False when RouDi does
  // not know it.
  bool remove_process(const std::string& name);

  // Stops RouDi's threads (its socket goes with them), leaving its memory as it is.
  void stop();
};

}  // namespace afhub

// RouDi without keep-alive monitoring (see afhub_roudi.hpp).
#include "afhub_roudi.hpp"

namespace afhub {

// The hub does not kill clients when it stops: they keep running and re-attach.
AfhubRouDi::AfhubRouDi(iox::roudi::RouDiMemoryInterface& memory, iox::roudi::PortManager& ports)
    : RouDi(memory, ports, RoudiStartupParameters{iox::roudi::MonitoringMode::OFF, false}) {
  // The pools are measured every 100 ms rather than every second: a new process checks
  // the chunks it needs by them (require_chunks), so they must be recent.
  m_mempoolIntrospection.setSendInterval(iox::units::Duration::fromMilliseconds(100));
}

AfhubRouDi::~AfhubRouDi() = default;

bool AfhubRouDi::remove_process(const std::string& name) {
  return m_prcMgr->unregisterProcess(iox::RuntimeName_t(iox::cxx::TruncateToCapacity, name));
}

void AfhubRouDi::stop() {
  shutdown();
}

}  // namespace afhub

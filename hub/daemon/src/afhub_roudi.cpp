// RouDi without keep-alive monitoring (see afhub_roudi.hpp).
#include "afhub_roudi.hpp"

namespace afhub {

// The hub does not kill clients when it stops: they keep running and re-attach.
AfhubRouDi::AfhubRouDi(iox::roudi::RouDiMemoryInterface& memory, iox::roudi::PortManager& ports)
    : RouDi(memory, ports, RoudiStartupParameters{iox::roudi::MonitoringMode::OFF, false}) {}

AfhubRouDi::~AfhubRouDi() = default;

bool AfhubRouDi::remove_process(const std::string& name) {
  return m_prcMgr->unregisterProcess(iox::RuntimeName_t(iox::cxx::TruncateToCapacity, name));
}

void AfhubRouDi::stop() {
  shutdown();
}

}  // namespace afhub

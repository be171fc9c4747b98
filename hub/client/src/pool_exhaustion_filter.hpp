// iceoryx 2.0.3 writes "Mempool [m_chunkSize = N, numberOfChunks = M, used_chunks = U ]
// has no more space left" straight to std::cerr at every loan a full pool refuses,
// whatever its log level: a loop out of chunks wrote it every step (133 MB of log in
// 4 s). std::cerr is passed through a filter that says it once per pool, in afhub's
// words ("shared memory exhausted", the pool and its size), and passes every other
// line as it was.
#pragma once

#include <string>

namespace afhub {

// Installs the filter on std::cerr, once per process; `who` names the process
// ("afhub run") in its message.
void filter_pool_exhaustion_lines(const std::string& who);

}  // namespace afhub

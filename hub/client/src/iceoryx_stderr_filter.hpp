// iceoryx 2.0.3 writes some lines straight to std::cerr, whatever its log level:
//   - "Mempool [m_chunkSize = N, numberOfChunks = M, used_chunks = U ] has no more space
//     left" at every loan a full pool refuses: a loop out of chunks wrote it every step
//     (133 MB of log in 4 s). Said once per pool instead, in afhub's words ("shared memory
//     exhausted", the pool and its size).
//   - "./iceoryx_hoofs/source/posix_wrapper/unix_domain_socket.cpp:249 { ... -> iox_sendto
//     } ::: [ 111 ] Connection refused" (or ENOENT, ENOTCONN), and "internal logic error
//     in unix domain socket "/tmp/roudi" occurred": a message to a hub that is gone (its
//     keep-alive, its farewell at exit; seen in fault-injection runs and, a line every
//     keep-alive, from a client left on a replaced hub). Dropped: afhub's hub-loss
//     handling says the hub went away, and what happens next.
// std::cerr is passed through a filter that does so and passes every other line as it was.
#pragma once

#include <memory>
#include <streambuf>
#include <string>

namespace afhub {

// Installs the filter on std::cerr, once per process; `who` names the process
// ("afhub run") in its messages.
void filter_iceoryx_stderr(const std::string& who);

// The filter alone, writing to `out` (for tests).
std::unique_ptr<std::streambuf> make_iceoryx_stderr_filter(std::streambuf* out, std::string who);

}  // namespace afhub

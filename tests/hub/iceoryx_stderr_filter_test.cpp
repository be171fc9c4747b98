// The filter on std::cerr of iceoryx's own lines (hub/client/src/iceoryx_stderr_filter.hpp),
// fed as iceoryx writes them: a line in pieces, std::cerr flushing after each.
#include "iceoryx_stderr_filter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace afhub {
namespace {

// Writes `pieces` as one `std::cerr << a << b << std::endl` does (unit-buffered).
void write_line(std::ostream& err, const std::vector<std::string>& pieces) {
  for (const std::string& piece : pieces) err << piece << std::flush;
  err << std::endl;
}

struct Filtered {
  std::stringbuf out;
  std::unique_ptr<std::streambuf> filter = make_iceoryx_stderr_filter(&out, "afhub test");
  std::ostream err{filter.get()};
};

// iceoryx's POSIX call wrapper, as Debian's build prints it, for errno `code`.
std::vector<std::string> socket_line(const std::string& code, const std::string& text) {
  return {"./iceoryx_hoofs/source/posix_wrapper/unix_domain_socket.cpp",
          ":249 { iox::cxx::expected<iox::posix::IpcChannelError> "
          "iox::posix::UnixDomainSocket::timedSend(const std::string&, const "
          "iox::units::Duration&) const -> iox_sendto }",
          "  :::  [ " + code + " ]  ", text};
}

TEST(IceoryxStderrFilter, LinesOfAHubGoneAreDropped) {
  Filtered f;
  write_line(f.err, socket_line("111", "Connection refused"));
  write_line(f.err, socket_line("107", "Transport endpoint is not connected"));
  write_line(f.err, socket_line("2", "No such file or directory"));
  write_line(f.err, {"internal logic error in unix domain socket \"/tmp/roudi\" occurred"});
  EXPECT_EQ(f.out.str(), "");
}

TEST(IceoryxStderrFilter, EveryOtherLineGoesThroughAsItWas) {
  Filtered f;
  // The same call failing otherwise (a permission), another file, afhub's own lines.
  write_line(f.err, socket_line("13", "Permission denied"));
  write_line(f.err, {"./iceoryx_hoofs/source/posix_wrapper/shared_memory.cpp:10 { x }  :::  "
                     "[ 111 ]  Connection refused"});
  write_line(f.err, {"internal logic error in unix domain socket \"/tmp/other\" occurred"});
  write_line(f.err, {"afhub run: ", "the hub went away"});
  const std::string out = f.out.str();
  EXPECT_NE(out.find("[ 13 ]  Permission denied\n"), std::string::npos) << out;
  EXPECT_NE(out.find("shared_memory.cpp:10"), std::string::npos) << out;
  EXPECT_NE(out.find("\"/tmp/other\" occurred\n"), std::string::npos) << out;
  EXPECT_NE(out.find("afhub run: the hub went away\n"), std::string::npos) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 4) << out;
}

TEST(IceoryxStderrFilter, AFullPoolIsSaidOncePerPool) {
  Filtered f;
  for (int i = 0; i < 3; ++i)
    write_line(f.err, {"Mempool [m_chunkSize = 1088, numberOfChunks = 64, used_chunks = 64 ]",
                       " has no more space left"});
  const std::string out = f.out.str();
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  EXPECT_NE(out.find("afhub test: shared memory exhausted: the hub's pool of 64 chunks"),
            std::string::npos)
      << out;
}

}  // namespace
}  // namespace afhub

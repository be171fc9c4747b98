// Who may use the viewer's server (viewer/include/afhub/viewer/page_access.hpp): the
// Host and Origin a request must have, and the command token.
#include "afhub/viewer/page_access.hpp"

#include <gtest/gtest.h>

namespace afhub::viewer {
namespace {

bool served(const char* bind, const char* host, const char* origin = nullptr) {
  return origin_problem(bind, 8080, host, origin).empty();
}

TEST(PageAccess, TheHostMustNameTheBoundAddressAndPort) {
  EXPECT_TRUE(served("127.0.0.1", "127.0.0.1:8080"));
  EXPECT_TRUE(served("127.0.0.1", "localhost:8080"));
  EXPECT_TRUE(served("127.0.0.1", "LocalHost:8080"));
  EXPECT_TRUE(served("127.0.0.1", "127.0.0.1"));  // no port: civetweb's WebSocket client
  EXPECT_TRUE(served("192.168.1.5", "192.168.1.5:8080"));
  EXPECT_TRUE(served("::1", "[::1]:8080"));
  // DNS rebinding: the attacker's name resolves to this machine.
  EXPECT_FALSE(served("127.0.0.1", "evil.example:8080"));
  EXPECT_FALSE(served("127.0.0.1", "127.0.0.1:8081"));
  EXPECT_FALSE(served("127.0.0.1", "127.0.0.1.evil.example:8080"));
  EXPECT_FALSE(served("192.168.1.5", "localhost:8080"));
  EXPECT_FALSE(served("127.0.0.1", nullptr));
  EXPECT_FALSE(served("127.0.0.1", ""));
  const std::string problem = origin_problem("127.0.0.1", 8080, "evil.example:8080", nullptr);
  EXPECT_NE(problem.find("evil.example:8080"), std::string::npos) << problem;
  EXPECT_NE(problem.find("http://127.0.0.1:8080"), std::string::npos) << problem;
}

TEST(PageAccess, AnOriginMustBeTheViewersOwn) {
  EXPECT_TRUE(served("127.0.0.1", "127.0.0.1:8080", "http://127.0.0.1:8080"));
  EXPECT_TRUE(served("127.0.0.1", "localhost:8080", "http://localhost:8080"));
  EXPECT_FALSE(served("127.0.0.1", "127.0.0.1:8080", "http://evil.example"));
  EXPECT_FALSE(served("127.0.0.1", "127.0.0.1:8080", "http://127.0.0.1:9999"));
  EXPECT_FALSE(served("127.0.0.1", "127.0.0.1:8080", "null"));
  EXPECT_FALSE(served("127.0.0.1", "127.0.0.1:8080", "https://127.0.0.1:8080"));
  // Bound to every address: any name the machine is reached by, but the page's origin
  // must be where it was loaded from.
  EXPECT_TRUE(served("0.0.0.0", "robot.lab:8080"));
  EXPECT_TRUE(served("0.0.0.0", "robot.lab:8080", "http://robot.lab:8080"));
  EXPECT_FALSE(served("0.0.0.0", "robot.lab:8080", "http://evil.example"));
  EXPECT_FALSE(served("0.0.0.0", nullptr));
}

TEST(PageAccess, ACommandNeedsTheExactToken) {
  const std::string token = random_token();
  EXPECT_EQ(token.size(), 32U);
  EXPECT_EQ(token.find_first_not_of("0123456789abcdef"), std::string::npos) << token;
  EXPECT_NE(random_token(), token);
  EXPECT_EQ(token_problem(token, token.c_str()), "");
  EXPECT_NE(token_problem(token, nullptr).find("no command token"), std::string::npos);
  EXPECT_NE(token_problem(token, "").find("wrong"), std::string::npos);
  EXPECT_NE(token_problem(token, token.substr(0, 31).c_str()), "");
  EXPECT_NE(token_problem(token, (token + "0").c_str()), "");
  std::string other = token;
  other[31] = other[31] == '0' ? '1' : '0';
  EXPECT_NE(token_problem(token, other.c_str()), "");
  EXPECT_NE(token_problem("", ""), "") << "no token set: nothing matches";
}

TEST(PageAccess, LoopbackAddresses) {
  EXPECT_TRUE(is_loopback("127.0.0.1"));
  EXPECT_TRUE(is_loopback("127.1.2.3"));
  EXPECT_TRUE(is_loopback("::1"));
  EXPECT_FALSE(is_loopback("0.0.0.0"));
  EXPECT_FALSE(is_loopback("::"));
  EXPECT_FALSE(is_loopback("192.168.1.5"));
  EXPECT_FALSE(is_loopback("localhost"));  // not an address: civetweb binds addresses
}

}  // namespace
}  // namespace afhub::viewer

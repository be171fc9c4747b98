// Channel names: normalisation, iceoryx's length limit, and lookup by suffix.
#include "afhub/shm_layout/channel_names.hpp"

#include <gtest/gtest.h>

#include "afhub/shm_layout/error.hpp"

namespace afhub {
namespace {

TEST(ChannelNames, JoinsNamespaceAndBodyLikeAmbf) {
  EXPECT_EQ(body_channel_name("/ambf/env/", "base link"), "ambf/env/baselink");
  EXPECT_EQ(body_channel_name("ambf//env", "/link1"), "ambf/env/link1");
  EXPECT_EQ(body_channel_name("", "base"), "base");
}

TEST(ChannelNames, AcceptsOneHundredCharactersAndRejectsMore) {
  EXPECT_EQ(channel_name_problem(std::string(100, 'a')), "");
  std::string problem = channel_name_problem(std::string(101, 'a'));
  EXPECT_NE(problem.find("101 characters"), std::string::npos) << problem;
  EXPECT_NE(problem.find("at most 100"), std::string::npos) << problem;
  EXPECT_THROW(body_state_channel(std::string(101, 'a')), Error);
}

TEST(ChannelNames, RejectsEmptyNamesAndOddCharacters) {
  EXPECT_NE(channel_name_problem(""), "");
  EXPECT_NE(channel_name_problem("ambf/env/a b").find("' '"), std::string::npos);
  EXPECT_NE(channel_name_problem("ambf/env/a*b"), "");
}

TEST(ChannelNames, BodyChannelsUseTheAfhubService) {
  ChannelId state = body_state_channel("ambf/env/base");
  EXPECT_EQ(state.service, "afhub");
  EXPECT_EQ(state.instance, "ambf/env/base");
  EXPECT_EQ(state.event, "state");
  EXPECT_EQ(body_command_channel("ambf/env/base").event, "command");
}

const std::vector<std::string> kLive = {"ambf/env/base", "ambf/env/link1", "psm1/link1",
                                        "ambf/env/baselink"};

TEST(ResolveBody, FindsExactNamesAndUniqueSuffixes) {
  EXPECT_EQ(resolve_body("ambf/env/link1", kLive), "ambf/env/link1");
  EXPECT_EQ(resolve_body("base", kLive), "ambf/env/base");
  EXPECT_EQ(resolve_body("env/link1", kLive), "ambf/env/link1");
  EXPECT_EQ(resolve_body("psm1/link1", kLive), "psm1/link1");
}

TEST(ResolveBody, SuffixesStartAtASlash) {
  // "link" is not a suffix of "baselink" on a name boundary.
  EXPECT_THROW(resolve_body("link", kLive), Error);
}

TEST(ResolveBody, AmbiguousNamesListTheCandidates) {
  try {
    resolve_body("link1", kLive);
    FAIL() << "expected an ambiguity error";
  } catch (const Error& error) {
    std::string message = error.what();
    EXPECT_NE(message.find("ambiguous"), std::string::npos) << message;
    EXPECT_NE(message.find("ambf/env/link1"), std::string::npos) << message;
    EXPECT_NE(message.find("psm1/link1"), std::string::npos) << message;
  }
}

TEST(ResolveBody, UnknownNamesListTheLiveBodies) {
  try {
    resolve_body("gripper", kLive);
    FAIL() << "expected an unknown-body error";
  } catch (const Error& error) {
    std::string message = error.what();
    EXPECT_NE(message.find("gripper"), std::string::npos) << message;
    EXPECT_NE(message.find("ambf/env/base"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace afhub

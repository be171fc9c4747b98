// Claims off the DDS bridge's loop (bridges/dds/src/mirror_claims.hpp): a claim under
// way holds up none of the loop's calls, the queue is bounded, states of a name being
// claimed are counted as dropped, and a refused name is not claimed again until its
// retry time has passed (refused_names.hpp), within a bounded table.
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <string>
#include <thread>

#include "afhub/shm_layout/error.hpp"
#include "mirror_claims.hpp"
#include "refused_names.hpp"

namespace afhub::bridges {
namespace {

TEST(RefusedNames, SaysANameOnceAndRetriesItAfterItsTime) {
  RefusedNames refused(4, 100);
  EXPECT_TRUE(refused.add("peer/a", 1000));
  EXPECT_FALSE(refused.add("peer/a", 1010));  // listed already: not said again
  EXPECT_TRUE(refused.recent("peer/a", 1109));
  EXPECT_FALSE(refused.recent("peer/a", 1110));
  EXPECT_FALSE(refused.recent("peer/b", 1000));
  EXPECT_EQ(refused.size(), 1u);
}

TEST(RefusedNames, FullForgetsTheNameRefusedLongestAgo) {
  RefusedNames refused(2, 1000);
  refused.add("peer/a", 10);
  refused.add("peer/b", 20);
  refused.add("peer/a", 30);  // a again: now b is the oldest
  EXPECT_TRUE(refused.add("peer/c", 40));
  EXPECT_EQ(refused.size(), 2u);
  EXPECT_TRUE(refused.recent("peer/a", 50));
  EXPECT_FALSE(refused.recent("peer/b", 50));
  EXPECT_TRUE(refused.recent("peer/c", 50));
}

// Calls install_claimed() until `done` holds (a claim's thread finishing), at most 10 s.
void install_until(MirrorClaims& claims, const bool& done) {
  for (int i = 0; i < 10000 && !done; ++i) {
    claims.install_claimed();
    if (!done) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

TEST(MirrorClaims, AClaimUnderWayHoldsUpNeitherAskingNorStates) {
  MirrorClaims claims({.max_pending = 2, .max_refused = 8, .retry_after_ns = 1'000'000'000'000});
  std::promise<void> started, release;
  std::shared_future<void> released = release.get_future().share();
  bool slow_installed = false, quick_installed = false;
  ASSERT_TRUE(claims.ask("peer/slow", [&, released]() -> MirrorClaims::Install {
    started.set_value();
    released.wait();
    return [&] { slow_installed = true; };
  }));
  started.get_future().wait();  // the claim of peer/slow is under way and stays so
  EXPECT_FALSE(claims.may_ask("peer/slow"));
  EXPECT_TRUE(claims.drop_if_pending("peer/slow"));
  EXPECT_FALSE(claims.drop_if_pending("peer/other"));
  ASSERT_TRUE(claims.ask(
      "peer/quick", [&]() -> MirrorClaims::Install { return [&] { quick_installed = true; }; }));
  EXPECT_FALSE(claims.has_room());  // two pending: the most
  EXPECT_FALSE(claims.ask("peer/third", [] { return MirrorClaims::Install([] {}); }));
  claims.install_claimed();  // nothing done yet; returns at once
  EXPECT_FALSE(slow_installed);
  EXPECT_EQ(claims.counts().pending, 2u);
  EXPECT_EQ(claims.counts().states_dropped, 1u);
  release.set_value();
  install_until(claims, quick_installed);
  EXPECT_TRUE(slow_installed);  // in the order asked
  EXPECT_TRUE(quick_installed);
  EXPECT_EQ(claims.counts().pending, 0u);
  EXPECT_TRUE(claims.has_room());
}

TEST(MirrorClaims, ARefusedNameIsNotAskedForUntilItsRetryTime) {
  MirrorClaims never({.max_pending = 4, .max_refused = 8, .retry_after_ns = 1'000'000'000'000});
  MirrorClaims at_once({.max_pending = 4, .max_refused = 8, .retry_after_ns = 0});
  bool installed = false;
  for (MirrorClaims* claims : {&never, &at_once}) {
    ASSERT_TRUE(
        claims->ask("peer/big", []() -> MirrorClaims::Install { throw Error("it does not fit"); }));
    // The refusal is recorded on the claims' thread: the marker after it shows it done.
    installed = false;
    ASSERT_TRUE(claims->ask("peer/marker",
                            [&]() -> MirrorClaims::Install { return [&] { installed = true; }; }));
    install_until(*claims, installed);
    ASSERT_TRUE(installed);
    EXPECT_EQ(claims->counts().refusals, 1u);
    EXPECT_EQ(claims->counts().refused, 1u);
  }
  EXPECT_FALSE(never.may_ask("peer/big"));
  EXPECT_FALSE(never.ask("peer/big", [] { return MirrorClaims::Install([] {}); }));
  EXPECT_TRUE(at_once.may_ask("peer/big"));
}

}  // namespace
}  // namespace afhub::bridges

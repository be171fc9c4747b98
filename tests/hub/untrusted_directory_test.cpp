// Directories from other processes are untrusted: a process publishing a malformed
// one (a body name that cannot be a channel, a joint count beyond its array, a name
// with no terminating NUL) while the hub serves is refused, named in the hub's log,
// and the hub lives on: the other bodies keep appearing in the catalog.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub_process.hpp"

namespace afhub {
namespace {

using namespace std::chrono_literals;

// A directory channel as any process may open one, publishing `bodies` as they are.
class RawDirectory {
 public:
  explicit RawDirectory(const std::string& instance)
      : writer_({std::string(kService), instance, std::string(kDirectoryEvent)},
                PayloadKind::kBodyDirectory) {}
  void publish(const std::vector<BodyInfo>& bodies) {
    auto* list = static_cast<BodyList*>(writer_.loan(body_list_bytes(bodies.size())));
    ASSERT_NE(list, nullptr);
    std::memset(static_cast<void*>(list), 0, body_list_bytes(bodies.size()));
    list->body_count = static_cast<std::uint32_t>(bodies.size());
    for (std::size_t i = 0; i < bodies.size(); ++i) list->bodies[i] = bodies[i];
    writer_.publish(list);
  }

 private:
  RawWriter writer_;
};

BodyInfo body_named(const std::string& channel) {
  BodyInfo body{};
  set_name(body.channel, channel);
  set_name(body.owner, "untrusted");
  return body;
}

bool catalog_lists(CatalogReader& catalog, const std::string& channel) {
  const std::vector<std::string> channels = catalog.channels();
  return std::find(channels.begin(), channels.end(), channel) != channels.end();
}

TEST(UntrustedDirectory, ABadDirectoryNeverStopsTheHubNorHidesTheOthers) {
  const auto hub_pid = running_hub_pid();
  ASSERT_TRUE(hub_pid);
  CatalogReader catalog;
  catalog.wait(2000ms);

  RawDirectory bad_name("untrusted-bad-name");
  bad_name.publish({body_named("untrusted/fine"), body_named("bad name!")});
  RawDirectory too_many_joints("untrusted-too-many-joints");
  BodyInfo many = body_named("untrusted/many");
  many.joint_count = 100000;
  too_many_joints.publish({many});
  RawDirectory unterminated("untrusted-unterminated");
  BodyInfo long_name = body_named("x");
  long_name.channel.fill('a');  // no NUL: 104 characters, beyond iceoryx's 100
  unterminated.publish({long_name});

  // A good directory published after them still joins the catalog.
  DirectoryPublisher good;
  good.add(make_body_entry("untrusted/good", {"j0"}));
  good.publish();
  EXPECT_TRUE(test::wait_until([&] { return catalog_lists(catalog, "untrusted/good"); }, 5s))
      << "the hub's log:\n"
      << test::read_file("/tmp/afhub-test-hub.log");
  EXPECT_LT(test::exit_code_if_ended(*hub_pid), 0) << "the hub is gone";

  // And so does one published later still: the hub keeps merging.
  RawDirectory later("untrusted-later");
  later.publish({body_named("untrusted/later")});
  EXPECT_TRUE(test::wait_until([&] { return catalog_lists(catalog, "untrusted/later"); }, 5s));

  // The malformed directories are refused whole, never listed.
  for (const std::string& channel : catalog.channels()) {
    EXPECT_NE(channel, "untrusted/fine") << "a body of a refused directory is listed";
    EXPECT_NE(channel, "untrusted/many");
    EXPECT_EQ(channel.find("aaaa"), std::string::npos);
  }
  const std::string log = test::read_file("/tmp/afhub-test-hub.log");
  EXPECT_TRUE(test::contains(log, "the directory of untrusted-bad-name is refused")) << log;
  EXPECT_TRUE(test::contains(log, "BodyInfo.channel")) << log;
  EXPECT_TRUE(test::contains(log, "BodyInfo.joint_count")) << log;
}

// Every member of the hub's group can write a published chunk. A writer that flips a
// joint reference of its directory past the names, over and over while the hub reads
// it, must not take the hub down: the hub checks a copy and uses only that copy (a
// check in place passes, and the second read of the reference then points 32 GB away).
TEST(UntrustedDirectory, ADirectoryChangedWhileTheHubReadsItNeverStopsTheHub) {
  const auto hub_pid = running_hub_pid();
  ASSERT_TRUE(hub_pid);
  CatalogReader catalog;
  catalog.wait(2000ms);
  RawWriter writer({std::string(kService), "untrusted-flipper", std::string(kDirectoryEvent)},
                   PayloadKind::kBodyDirectory);
  // Many bodies, so that the hub's use of the last one's joint reference comes well after
  // its check of the whole directory.
  constexpr std::uint32_t kBodies = 300;
  const auto publish = [&writer] {
    const std::size_t bytes = body_list_bytes(kBodies, 1, kBodies);
    auto* list = static_cast<BodyList*>(writer.loan(bytes));
    if (!list) return static_cast<std::uint32_t*>(nullptr);
    std::memset(static_cast<void*>(list), 0, bytes);
    list->body_count = kBodies;
    list->joint_name_count = 1;
    list->joint_ref_count = kBodies;
    for (std::uint32_t i = 0; i < kBodies; ++i) {
      list->bodies[i] = body_named("untrusted/flipper" + std::to_string(i));
      list->bodies[i].joint_count = 1;
      list->bodies[i].first_joint_ref = i;
    }
    set_name(joint_names_in(*list)[0], "j0");
    std::uint32_t* last_ref = joint_refs_in(*list) + kBodies - 1;
    writer.publish(list);
    return last_ref;
  };

  std::atomic<std::uint32_t*> flipped{nullptr};
  std::atomic<bool> done{false};
  std::thread flipper([&] {
    while (!done)
      if (volatile std::uint32_t* ref = flipped.load()) {
        *ref = 0x7fffffff;
        *ref = 0;
      }
  });
  // (The hub is this process's child: a crashed one stays a zombie until reaped.)
  int hub_exit = -1;
  for (int i = 0; i < 3000 && (hub_exit = test::exit_code_if_ended(*hub_pid)) < 0; ++i) {
    flipped = publish();
    std::this_thread::sleep_for(1ms);
  }
  done = true;
  flipper.join();
  ASSERT_LT(hub_exit, 0) << "the hub is gone (exit " << hub_exit << "); its log:\n"
                         << test::read_file("/tmp/afhub-test-hub.log");

  // Once the writer stops changing it, its directory is listed.
  publish();
  EXPECT_TRUE(test::wait_until([&] { return catalog_lists(catalog, "untrusted/flipper299"); }, 5s))
      << test::read_file("/tmp/afhub-test-hub.log");
}

}  // namespace
}  // namespace afhub

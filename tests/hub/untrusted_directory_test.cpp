// Directories from other processes are untrusted: a process publishing a malformed
// one (a body name that cannot be a channel, a joint count beyond its array, a name
// with no terminating NUL) while the hub serves is refused, named in the hub's log,
// and the hub lives on: the other bodies keep appearing in the catalog.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <cstring>
#include <string>
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
  EXPECT_EQ(kill(*hub_pid, 0), 0) << "the hub is gone";

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

}  // namespace
}  // namespace afhub

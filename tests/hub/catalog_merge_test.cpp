// The catalog's merge on its own, with no hub: a directory holding a body that
// cannot be a channel is refused whole and named; the others are listed.
#include "catalog_merge.hpp"

#include <gtest/gtest.h>

#include <memory>

#include "afhub/hub/bodies.hpp"

namespace afhub {
namespace {

std::unique_ptr<BodyList> list_of(const std::vector<std::string>& channels) {
  auto list = std::make_unique<BodyList>();
  list->body_count = static_cast<std::uint32_t>(channels.size());
  for (std::size_t i = 0; i < channels.size(); ++i) set_name(list->bodies[i].channel, channels[i]);
  return list;
}

std::vector<std::string> names(const std::vector<BodyEntry>& bodies) {
  std::vector<std::string> out;
  for (const BodyEntry& body : bodies) out.emplace_back(name_of(body.info.channel));
  return out;
}

TEST(CatalogMerge, RefusesADirectoryWithABadBodyWholeAndListsTheOthers) {
  auto good = list_of({"a/one", "a/two"});
  auto bad = list_of({"b/fine", "b/no good"});
  auto late = list_of({"c/three"});
  std::vector<std::string> messages;
  const auto merged = merge_directories(
      {}, {{"good", good.get()}, {"bad", bad.get()}, {"late", late.get()}}, messages);
  EXPECT_EQ(names(merged), (std::vector<std::string>{"a/one", "a/two", "c/three"}));
  ASSERT_EQ(messages.size(), 1u);
  EXPECT_NE(messages[0].find("the directory of bad is refused"), std::string::npos) << messages[0];
  EXPECT_NE(messages[0].find("body 1: BodyInfo.channel"), std::string::npos) << messages[0];
}

TEST(CatalogMerge, NamesEveryProblemOfABodyEntry) {
  BodyInfo body{};
  EXPECT_NE(body_info_problem(body).find("empty"), std::string::npos);
  body.channel.fill('a');  // no terminating NUL: read up to the buffer's end, too long
  EXPECT_NE(body_info_problem(body).find("characters"), std::string::npos);
  set_name(body.channel, "ok/body");
  EXPECT_EQ(body_info_problem(body), "");
  body.joint_count = kMaxJointsPerBody + 1;
  EXPECT_NE(body_info_problem(body).find("BodyInfo.joint_count"), std::string::npos);
}

TEST(CatalogMerge, ListedBodiesKeepTheirPlaceAndTheirOwner) {
  auto first = list_of({"x/shared", "x/own"});
  auto second = list_of({"x/shared"});
  first->bodies[0].owner_pid = 1;
  second->bodies[0].owner_pid = 2;
  std::vector<std::string> messages;
  // The catalog lists x/shared as the second process's: it stays with it.
  std::vector<BodyEntry> listed{{second->bodies[0], {}}};
  const auto merged =
      merge_directories(listed, {{"first", first.get()}, {"second", second.get()}}, messages);
  ASSERT_EQ(names(merged), (std::vector<std::string>{"x/shared", "x/own"}));
  EXPECT_EQ(merged[0].info.owner_pid, 2u);
  ASSERT_EQ(messages.size(), 1u);
  EXPECT_NE(messages[0].find("claimed by two processes"), std::string::npos);
}

}  // namespace
}  // namespace afhub

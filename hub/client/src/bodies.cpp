// Body channels and the catalog (see bodies.hpp).
#include "afhub/hub/bodies.hpp"

#include <unistd.h>

#include <time.h>

#include <cstdio>
#include <cstring>
#include <limits>
#include <thread>

#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"

namespace afhub {

BodyPublisher::BodyPublisher(std::string_view body_channel)
    : channel_(body_channel),
      state_(body_state_channel(body_channel)),
      command_(body_command_channel(body_channel)) {}

BodyClient::BodyClient(std::string_view body_channel)
    : channel_(body_channel),
      state_(body_state_channel(body_channel)),
      command_(body_command_channel(body_channel)) {}

BodyClient::BodyClient(const BodyInfo& info) : BodyClient(name_of(info.channel)) {
  joint_names_ = joint_names_of(info);
  joint_names_known_ = true;
}

const std::vector<std::string>& BodyClient::joint_names() {
  if (!joint_names_known_) {
    CatalogReader catalog;
    catalog.wait(std::chrono::milliseconds(1000));
    joint_names_ = joint_names_of(catalog.resolve(channel_));
    joint_names_known_ = true;
  }
  return joint_names_;
}

std::size_t BodyClient::joint_index(std::string_view name) {
  const std::vector<std::string>& names = joint_names();
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return i;
  std::string known;
  for (std::size_t i = 0; i < names.size(); ++i)
    known += (i ? ", " : "") + std::to_string(i) + " " + names[i];
  throw Error(
      "body " + channel_ + " has no joint named '" + std::string(name) + "'; " +
      (names.empty() ? std::string("it has no joints") : "its joints are (index name): " + known));
}

std::vector<std::string> joint_names_of(const BodyInfo& info) {
  std::vector<std::string> names;
  for (std::uint32_t i = 0; i < info.joint_count && i < kMaxJointsPerBody; ++i)
    names.emplace_back(name_of(info.joint_names[i]));
  return names;
}

namespace {

template <std::size_t N>
void copy_name(std::array<char, N>& buffer, std::string_view text, std::string_view what) {
  if (text.size() >= N)
    throw Error(std::string(what) + " '" + std::string(text) + "' has " +
                std::to_string(text.size()) + " characters; at most " + std::to_string(N - 1) +
                " fit");
  buffer.fill('\0');
  std::memcpy(buffer.data(), text.data(), text.size());
}

}  // namespace

BodyInfo make_body_info(std::string_view body_channel,
                        const std::vector<std::string>& joint_names) {
  require_valid_channel_name(body_channel);
  if (joint_names.size() > kMaxJointsPerBody)
    throw Error("body '" + std::string(body_channel) + "' has " +
                std::to_string(joint_names.size()) + " descendant joints; afhub carries at most " +
                std::to_string(kMaxJointsPerBody) + " per body (kMaxJointsPerBody)");
  BodyInfo info;
  copy_name(info.channel, body_channel, "body channel");
  copy_name(info.owner, runtime_name(), "process name");
  info.owner_pid = static_cast<std::uint32_t>(getpid());
  info.joint_count = static_cast<std::uint32_t>(joint_names.size());
  for (std::size_t i = 0; i < joint_names.size(); ++i)
    copy_name(info.joint_names[i], joint_names[i], "joint name");
  return info;
}

DirectoryPublisher::DirectoryPublisher()
    : writer_({std::string(kService), runtime_name(), std::string(kDirectoryEvent)},
              PayloadKind::kBodyDirectory) {
  if (runtime_name().empty()) throw Error("DirectoryPublisher needs connect_to_hub() first");
}

void DirectoryPublisher::add(const BodyInfo& body) {
  if (bodies_.size() >= kMaxBodies)
    throw Error("a process can own at most " + std::to_string(kMaxBodies) + " bodies");
  bodies_.push_back(body);
}

void DirectoryPublisher::publish() {
  auto* list = static_cast<BodyList*>(writer_.loan(body_list_bytes(bodies_.size())));
  if (!list) throw Error("shared memory is exhausted: cannot publish the body directory");
  list->header = PayloadHeader{};
  list->body_count = static_cast<std::uint32_t>(bodies_.size());
  for (std::size_t i = 0; i < bodies_.size(); ++i) list->bodies[i] = bodies_[i];
  writer_.publish(list);
}

CatalogReader::CatalogReader()
    : reader_({std::string(kService), std::string(kHubInstance), std::string(kCatalogEvent)},
              PayloadKind::kCatalog) {}

void CatalogReader::wait(std::chrono::milliseconds timeout) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!(current_ = static_cast<const BodyList*>(reader_.latest()))) {
    if (std::chrono::steady_clock::now() > deadline)
      throw Error(
          "a RouDi answers but publishes no afhub catalog: it is not an afhub hub (a plain "
          "iox-roudi?). Stop it and start `afhub hub`.");
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

const BodyList& CatalogReader::latest() noexcept {
  if (const void* newest = reader_.latest()) current_ = static_cast<const BodyList*>(newest);
  return *current_;
}

std::vector<std::string> CatalogReader::channels() {
  const BodyList& list = latest();
  std::vector<std::string> names;
  for (std::uint32_t i = 0; i < list.body_count; ++i)
    names.emplace_back(name_of(list.bodies[i].channel));
  return names;
}

BodyInfo CatalogReader::resolve(std::string_view query) {
  std::string channel = resolve_body(query, channels());
  const BodyList& list = latest();
  for (std::uint32_t i = 0; i < list.body_count; ++i)
    if (name_of(list.bodies[i].channel) == channel) return list.bodies[i];
  throw Error("body '" + channel + "' left the catalog while it was looked up");
}

BodyInfo wait_for_body(const std::string& query, const std::string& who, std::int64_t give_up_ns,
                       const std::string& hint) {
  CatalogReader catalog;
  catalog.wait(std::chrono::milliseconds(1000));
  bool said = false;
  for (;;) {
    try {
      return catalog.resolve(query);
    } catch (const Error& error) {
      if (monotonic_ns() > give_up_ns || stop_requested()) {
        if (!said) throw;
        throw Error(std::string(error.what()) + " (waited for it" +
                    (hint.empty() ? "" : "; " + hint) + ")");
      }
      if (!said) {
        if (give_up_ns == std::numeric_limits<std::int64_t>::max())
          std::fprintf(stderr, "%s: no body '%s' is live yet; waiting for it\n", who.c_str(),
                       query.c_str());
        else
          std::fprintf(stderr, "%s: no body '%s' is live yet; waiting up to %.3g s for it\n",
                       who.c_str(), query.c_str(),
                       static_cast<double>(give_up_ns - monotonic_ns()) * 1e-9);
      }
      said = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

}  // namespace afhub

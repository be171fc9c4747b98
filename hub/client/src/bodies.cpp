// Body channels and the catalog (see bodies.hpp).
#include "afhub/hub/bodies.hpp"

#include <fnmatch.h>
#include <unistd.h>

#include <time.h>

#include <atomic>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <thread>
#include <unordered_map>

#include "afhub/hub/hub_files.hpp"
#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/rt/stop_signal.hpp"
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

BodyClient::BodyClient(const BodyEntry& entry) : BodyClient(name_of(entry.info.channel)) {
  joint_names_ = entry.joint_names;
  joint_names_known_ = true;
}

const std::vector<std::string>& BodyClient::joint_names() {
  if (!joint_names_known_) {
    CatalogReader catalog;
    catalog.wait(std::chrono::milliseconds(1000));
    joint_names_ = catalog.resolve(channel_).joint_names;
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

namespace {

// The `count` names referenced from `first` on in `list`.
std::vector<std::string> names_at(const BodyList& list, std::uint64_t first, std::uint32_t count) {
  const JointName* names = joint_names_in(list);
  const std::uint32_t* refs = joint_refs_in(list) + first;
  std::vector<std::string> found;
  found.reserve(count);
  for (std::uint32_t i = 0; i < count; ++i) found.emplace_back(name_of(names[refs[i]]));
  return found;
}

}  // namespace

std::vector<std::string> joint_names_of(const BodyList& list, const BodyInfo& body) {
  return names_at(list, body.first_joint_ref, body.joint_count);
}

BodyEntry entry_of(const BodyList& list, std::uint32_t index) {
  const BodyInfo& body = list.bodies[index];
  BodyEntry entry{body, joint_names_of(list, body)};
  std::uint64_t at = std::uint64_t{body.first_joint_ref} + body.joint_count;
  entry.sensor_rays = names_at(list, at, body.sensor_ray_count);
  at += body.sensor_ray_count;
  entry.actuator_names = names_at(list, at, body.actuator_count);
  at += body.actuator_count;
  entry.child_names = names_at(list, at, body.child_count);
  at += body.child_count;
  if (body.parent_count == 1) entry.parent_name = names_at(list, at, 1).front();
  return entry;
}

BodyList* loan_body_list(RawWriter& writer, const std::vector<BodyEntry>& entries) {
  std::vector<std::string_view> names;
  std::unordered_map<std::string_view, std::uint32_t> name_index;
  std::vector<std::uint32_t> refs;
  const auto refer = [&](std::string_view name) {
    const auto [at, added] = name_index.emplace(name, static_cast<std::uint32_t>(names.size()));
    if (added) names.push_back(name);
    refs.push_back(at->second);
  };
  // In the order BodyInfo gives.
  for (const BodyEntry& entry : entries) {
    for (const std::string& name : entry.joint_names) refer(name);
    for (const std::string& name : entry.sensor_rays) refer(name);
    for (const std::string& name : entry.actuator_names) refer(name);
    for (const std::string& name : entry.child_names) refer(name);
    if (!entry.parent_name.empty()) refer(entry.parent_name);
  }
  // Past the largest tier no pool holds the list (iceoryx would abort the loan).
  if (entries.size() > kMaxBodies || names.size() > kMaxCatalogJointNames ||
      refs.size() > kMaxCatalogJointRefs ||
      body_list_bytes(entries.size(), names.size(), refs.size()) > kBodyListTiers.back())
    return nullptr;
  auto* list = static_cast<BodyList*>(writer.loan(
      static_cast<std::uint32_t>(body_list_loan_bytes(entries.size(), names.size(), refs.size()))));
  if (!list) return nullptr;
  list->header = PayloadHeader{};
  list->body_count = static_cast<std::uint32_t>(entries.size());
  list->joint_name_count = static_cast<std::uint32_t>(names.size());
  list->joint_ref_count = static_cast<std::uint32_t>(refs.size());
  list->reserved = 0;
  std::uint32_t first_ref = 0;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    list->bodies[i] = entries[i].info;
    BodyInfo& body = list->bodies[i];
    body.joint_count = static_cast<std::uint32_t>(entries[i].joint_names.size());
    body.sensor_ray_count = static_cast<std::uint32_t>(entries[i].sensor_rays.size());
    body.actuator_count = static_cast<std::uint32_t>(entries[i].actuator_names.size());
    body.child_count = static_cast<std::uint32_t>(entries[i].child_names.size());
    body.parent_count = entries[i].parent_name.empty() ? 0 : 1;
    body.first_joint_ref = first_ref;
    first_ref += static_cast<std::uint32_t>(body_ref_count(body));
  }
  JointName* name_slots = joint_names_in(*list);
  for (std::size_t n = 0; n < names.size(); ++n) set_name(name_slots[n], names[n]);
  std::copy(refs.begin(), refs.end(), joint_refs_in(*list));
  return list;
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

// afhub processes attached to the hub: each one's iceoryx runtime holds a lock on
// /tmp/afhub-<role>-<pid>.lock (connect_to_hub names them so).
std::size_t attached_processes() {
  std::size_t count = 0;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator("/tmp", error)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("afhub-") && name.ends_with(".lock") && flock_held(entry.path())) ++count;
  }
  return count;
}

}  // namespace

BodyEntry make_body_entry(std::string_view body_channel,
                          const std::vector<std::string>& joint_names) {
  require_valid_channel_name(body_channel);
  if (joint_names.size() > kMaxJointsPerBody)
    throw Error("body '" + std::string(body_channel) + "' has " +
                std::to_string(joint_names.size()) + " descendant joints; afhub carries at most " +
                std::to_string(kMaxJointsPerBody) + " per body (kMaxJointsPerBody)");
  BodyEntry entry;
  copy_name(entry.info.channel, body_channel, "body channel");
  copy_name(entry.info.owner, runtime_name(), "process name");
  entry.info.owner_pid = static_cast<std::uint32_t>(getpid());
  entry.info.joint_count = static_cast<std::uint32_t>(joint_names.size());
  JointName checked{};
  for (const std::string& name : joint_names) copy_name(checked, name, "joint name");
  entry.joint_names = joint_names;
  return entry;
}

void set_body_parts(BodyEntry& entry, std::vector<std::string> sensor_rays,
                    std::vector<std::string> actuator_names, std::vector<std::string> child_names,
                    std::string parent_name) {
  const std::string body(name_of(entry.info.channel));
  const auto bound = [&](std::size_t count, std::size_t most, std::string_view what,
                         std::string_view limit) {
    if (count > most)
      throw Error("body '" + body + "' has " + std::to_string(count) + " " + std::string(what) +
                  "; afhub carries at most " + std::to_string(most) + " per body (" +
                  std::string(limit) + ")");
  };
  bound(sensor_rays.size(), kMaxSensorRaysPerBody, "proximity-sensor rays",
        "kMaxSensorRaysPerBody");
  bound(actuator_names.size(), kMaxActuatorsPerBody, "actuators", "kMaxActuatorsPerBody");
  bound(child_names.size(), kMaxModelBodies, "child bodies", "kMaxModelBodies");
  JointName checked{};
  for (const auto* names : {&sensor_rays, &actuator_names, &child_names})
    for (const std::string& name : *names) copy_name(checked, name, "name of a part of " + body);
  copy_name(checked, parent_name, "parent name of " + body);
  entry.sensor_rays = std::move(sensor_rays);
  entry.actuator_names = std::move(actuator_names);
  entry.child_names = std::move(child_names);
  entry.parent_name = std::move(parent_name);
}

BodyEntry make_device_entry(std::string_view device_name) {
  BodyEntry entry = make_body_entry(device_channel_name(device_name), {});
  entry.info.kind = ChannelKind::kDevice;
  return entry;
}

namespace {

// A channel of its own for each directory: a process may own bodies through several
// (the physics and a device driver in one test binary), and the hub keeps the latest
// sample of a channel only, so that on one channel each would hide the other's bodies.
std::string next_directory_instance() {
  if (runtime_name().empty()) throw Error("DirectoryPublisher needs connect_to_hub() first");
  static std::atomic<unsigned> count{0};
  return runtime_name() + "/" + std::to_string(count++);
}

}  // namespace

DirectoryPublisher::DirectoryPublisher()
    : writer_({std::string(kService), next_directory_instance(), std::string(kDirectoryEvent)},
              PayloadKind::kBodyDirectory) {}

void DirectoryPublisher::add(const BodyEntry& body) {
  if (bodies_.size() >= kMaxBodies)
    throw Error("a process can own at most " + std::to_string(kMaxBodies) + " bodies");
  bodies_.push_back(body);
}

void DirectoryPublisher::publish() {
  BodyList* list = loan_body_list(writer_, bodies_);
  if (!list)
    throw Error("cannot publish the body directory of " + std::to_string(bodies_.size()) +
                " bodies: shared memory is exhausted, or they list more joint names than a "
                "catalog holds (" +
                std::to_string(kMaxCatalogJointRefs) +
                "); give the hub a larger pool (`afhub hub --pool BYTES:COUNT`)");
  writer_.publish(list);
}

CatalogReader::CatalogReader()
    : reader_({std::string(kService), std::string(kHubInstance), std::string(kCatalogEvent)},
              PayloadKind::kCatalog) {}

void CatalogReader::wait(std::chrono::milliseconds timeout) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!(current_ = static_cast<const BodyList*>(reader_.latest()))) {
    if (std::chrono::steady_clock::now() <= deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      continue;
    }
    // connect_to_hub checked that an afhub hub holds the RouDi's lock. iceoryx 2.0.3
    // does not tell a reader that the writer has no room for it: both causes are said.
    throw Error(
        "no catalog reached this process from the hub: either its catalog has all "
        "the readers iceoryx connects to one channel (" +
        std::to_string(kMaxReadersPerChannel) + ", kMaxReadersPerChannel; " +
        std::to_string(attached_processes()) +
        " afhub processes are attached: stop some, `afhub status` lists them), or "
        "the hub is starting or stuck (see its log)");
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

BodyEntry CatalogReader::resolve(std::string_view query) {
  std::string channel = resolve_body(query, channels());
  const BodyList& list = latest();
  for (std::uint32_t i = 0; i < list.body_count; ++i)
    if (name_of(list.bodies[i].channel) == channel) return entry_of(list, i);
  throw Error("body '" + channel + "' left the catalog while it was looked up");
}

BodyEntry wait_for_body(const std::string& query, const std::string& who, std::int64_t give_up_ns,
                        const std::string& hint, const char* kind) {
  // No name ('', '/', ' ') is no late body: refused at once.
  if (body_channel_name({}, query).empty()) resolve_body({}, {});
  CatalogReader catalog;
  catalog.wait(std::chrono::milliseconds(1000));
  bool said = false;
  for (;;) {
    try {
      return catalog.resolve(query);
    } catch (const Error& error) {
      if (stop_requested())
        throw Stopped(std::string("stopped while waiting for ") + kind + " '" + query + "'");
      if (monotonic_ns() > give_up_ns || hub_lost()) {
        if (!said) throw;
        throw Error(std::string(error.what()) + " (waited for it" +
                    (hint.empty() ? "" : "; " + hint) + ")");
      }
      if (!said) {
        if (give_up_ns == std::numeric_limits<std::int64_t>::max())
          std::fprintf(stderr, "%s: no %s '%s' is live yet; waiting for it\n", who.c_str(), kind,
                       query.c_str());
        else
          std::fprintf(stderr, "%s: no %s '%s' is live yet; waiting up to %.3g s for it\n",
                       who.c_str(), kind, query.c_str(),
                       static_cast<double>(give_up_ns - monotonic_ns()) * 1e-9);
      }
      said = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

bool matches_any(const std::string& channel, const std::vector<std::string>& globs) {
  for (const std::string& glob : globs) {
    if (fnmatch(glob.c_str(), channel.c_str(), 0) == 0) return true;
    // Its end after a '/', as names are given elsewhere (`afhub echo arm/base`).
    for (std::size_t slash = channel.find('/'); slash != std::string::npos;
         slash = channel.find('/', slash + 1))
      if (fnmatch(glob.c_str(), channel.c_str() + slash + 1, 0) == 0) return true;
  }
  return false;
}

}  // namespace afhub

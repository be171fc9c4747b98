// Channel naming and body lookup (see channel_names.hpp).
#include "afhub/shm_layout/channel_names.hpp"

#include <algorithm>

#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/limits.hpp"

namespace afhub {
namespace {

void append_segments(std::string& out, std::string_view path, bool drop_spaces) {
  std::size_t start = 0;
  while (start <= path.size()) {
    std::size_t end = path.find('/', start);
    if (end == std::string_view::npos) end = path.size();
    std::string segment(path.substr(start, end - start));
    if (drop_spaces) std::erase(segment, ' ');
    if (!segment.empty()) {
      if (!out.empty()) out += '/';
      out += segment;
    }
    start = end + 1;
  }
}

bool allowed_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
         c == '-' || c == '.' || c == '/';
}

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& name : names) out += (out.empty() ? "" : ", ") + name;
  return out.empty() ? "(none)" : out;
}

}  // namespace

std::string body_channel_name(std::string_view name_space, std::string_view body_name) {
  std::string out;
  append_segments(out, name_space, false);
  std::string body;
  append_segments(body, body_name, true);
  if (!body.empty()) out += (out.empty() ? "" : "/") + body;
  return out;
}

std::string channel_name_problem(std::string_view name) {
  if (name.empty()) return "the channel name is empty";
  if (name.size() > kMaxChannelNameLength)  // its start is enough to find it (a 10 MB name)
    return "the channel name '" + std::string(name.substr(0, kMaxChannelNameLength)) + "...' has " +
           std::to_string(name.size()) + " characters; iceoryx allows at most " +
           std::to_string(kMaxChannelNameLength) + ": shorten the namespace or the body name";
  for (char c : name)
    if (!allowed_char(c))
      return "the channel name '" + std::string(name) + "' contains '" + std::string(1, c) +
             "'; use letters, digits, '_', '-', '.' and '/'";
  return {};
}

void require_valid_channel_name(std::string_view name) {
  if (auto problem = channel_name_problem(name); !problem.empty()) throw Error(problem);
}

std::string world_instance(std::string_view name_space) {
  return name_space.empty() ? std::string(kWorldInstance)
                            : body_channel_name(name_space, kWorldInstance);
}

std::string device_channel_name(std::string_view device_name) {
  if (device_name.empty() || device_name.find('/') != std::string_view::npos)
    throw Error("device name '" + std::string(device_name) +
                "' must be one word without '/' (its channel is device/<name>)");
  std::string channel = "device/" + std::string(device_name);
  require_valid_channel_name(channel);
  return channel;
}

ChannelId body_state_channel(std::string_view body_channel) {
  require_valid_channel_name(body_channel);
  return {std::string(kService), std::string(body_channel), std::string(kStateEvent)};
}

ChannelId body_command_channel(std::string_view body_channel) {
  require_valid_channel_name(body_channel);
  return {std::string(kService), std::string(body_channel), std::string(kCommandEvent)};
}

std::string resolve_body(std::string_view query, const std::vector<std::string>& channels) {
  std::string wanted = body_channel_name("", query);
  if (wanted.empty())
    throw Error("no body name given: name a body, e.g. 'base' or 'ambf/env/base'");
  if (std::find(channels.begin(), channels.end(), wanted) != channels.end()) return wanted;
  std::vector<std::string> matches;
  for (const auto& channel : channels) {
    if (channel.size() > wanted.size() && channel.ends_with(wanted) &&
        channel[channel.size() - wanted.size() - 1] == '/')
      matches.push_back(channel);
  }
  if (matches.size() == 1) return matches.front();
  if (matches.empty())
    throw Error("no live body is named '" + wanted + "'; live bodies: " + join(channels) +
                " (see `afhub ls`)");
  throw Error("'" + wanted + "' is ambiguous: it matches " + join(matches) +
              "; give more of the name");
}

}  // namespace afhub

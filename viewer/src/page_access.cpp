// Who may use the viewer's server (see page_access.hpp).
#include "afhub/viewer/page_access.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <strings.h>
#include <unistd.h>

#include <cstdint>
#include <vector>

#include "afhub/shm_layout/error.hpp"

namespace afhub::viewer {
namespace {

bool same_text(std::string_view a, std::string_view b) {
  return a.size() == b.size() && strncasecmp(a.data(), b.data(), a.size()) == 0;
}

bool is_wildcard(std::string_view bind) {
  return bind == "0.0.0.0" || bind == "::";
}

// How a browser names the server in its Host header: the bound address (an IPv6 one
// in brackets), and localhost for 127.0.0.1.
std::vector<std::string> host_names(std::string_view bind) {
  std::vector<std::string> names;
  names.push_back(url_host(bind));
  if (bind == "127.0.0.1") names.emplace_back("localhost");
  return names;
}

}  // namespace

std::string random_token() {
  std::uint8_t bytes[16];
  const int fd = open("/dev/urandom", O_RDONLY | O_CLOEXEC);
  const bool read_all = fd >= 0 && read(fd, bytes, sizeof bytes) == sizeof bytes;
  if (fd >= 0) close(fd);
  if (!read_all)
    throw Error(
        "cannot read /dev/urandom for the viewer's command token; it is needed with "
        "--allow-commands");
  static const char kHex[] = "0123456789abcdef";
  std::string token;
  for (const std::uint8_t byte : bytes) {
    token += kHex[byte >> 4];
    token += kHex[byte & 15];
  }
  return token;
}

void require_ip_address(std::string_view address) {
  const std::string text(address);
  in_addr v4{};
  in6_addr v6{};
  if (inet_pton(AF_INET, text.c_str(), &v4) != 1 && inet_pton(AF_INET6, text.c_str(), &v6) != 1)
    throw Error("--bind takes an IP address of this machine (127.0.0.1, 0.0.0.0 for all), got '" +
                text + "'");
}

std::string url_host(std::string_view address) {
  return address.find(':') == std::string_view::npos ? std::string(address)
                                                     : "[" + std::string(address) + "]";
}

bool is_loopback(std::string_view address) {
  const std::string text(address);
  in_addr v4{};
  if (inet_pton(AF_INET, text.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  return inet_pton(AF_INET6, text.c_str(), &v6) == 1 && IN6_IS_ADDR_LOOPBACK(&v6);
}

std::string origin_problem(std::string_view bind, int port, const char* host, const char* origin) {
  if (!host || !*host) return "a request must name the viewer in its Host header";
  const std::string with_port = ":" + std::to_string(port);
  if (is_wildcard(bind)) {
    // Listening on every address, the viewer does not know the names it is reached by:
    // the page's origin must be where it was loaded from.
    if (origin && !same_text(origin, "http://" + std::string(host)))
      return "a page from " + std::string(origin) + " may not use the viewer at " + host;
    return "";
  }
  bool named = false, own_origin = false;
  for (const std::string& name : host_names(bind)) {
    // Without a port too: the tests' and civetweb's WebSocket client send none, and a
    // rebinding page could not send this name, only its own.
    named = named || same_text(host, name + with_port) || same_text(host, name);
    own_origin = own_origin || (origin && same_text(origin, "http://" + name + with_port));
  }
  const std::string viewer = "http://" + host_names(bind)[0] + with_port;
  if (!named)
    return "Host " + std::string(host) + " is not this viewer (" + viewer +
           "): open the page at the address `afhub view` printed";
  if (origin && !own_origin)
    return "a page from " + std::string(origin) + " may not use the viewer at " + viewer;
  return "";
}

std::string token_problem(std::string_view token, const char* sent) {
  const std::string_view given = sent ? sent : "";
  unsigned difference = given.size() == token.size() ? 0U : 1U;
  for (std::size_t i = 0; i < token.size(); ++i)
    difference |= static_cast<unsigned>(token[i] ^ (i < given.size() ? given[i] : 0));
  if (!token.empty() && difference == 0) return "";
  return std::string(sent ? "a wrong" : "no") +
         " command token: commands need the token in the URL `afhub view --allow-commands` "
         "printed (open the page at that URL: it sends the token in the X-Afhub-Token header)";
}

}  // namespace afhub::viewer

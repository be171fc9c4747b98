// Who may use the viewer's server. A web page the operator has open elsewhere can send
// requests to it (a cross-site request, or DNS rebinding: a name of the attacker's
// that resolves to this machine), so:
// - every request must name the viewer in its Host header (the bound address and
//   port, or localhost for 127.0.0.1), and its Origin, when it has one, must be the
//   viewer's own: another site's page is refused, its WebSocket too. Bound to every
//   address (0.0.0.0), the Host cannot be known, and the Origin must match the Host;
// - a command (POST /command, /world) must carry the token the viewer printed in
//   its URL (/?token=...), which the page reads from its own URL and sends in the
//   X-Afhub-Token header: no other page can know it.
#pragma once

#include <string>
#include <string_view>

namespace afhub::viewer {

// 128 random bits from /dev/urandom, as 32 hex digits; throws afhub::Error when
// /dev/urandom cannot be read.
std::string random_token();

// Whether `address` (an IPv4 or IPv6 literal) is a loopback address.
bool is_loopback(std::string_view address);

// Throws afhub::Error unless `address` is an IPv4 or IPv6 literal as inet_pton reads
// it: civetweb would listen on 231.1.1.1 for "999.1.1.1" (each part taken mod 256).
void require_ip_address(std::string_view address);

// `address` as a URL or a listening port names it: an IPv6 one in brackets.
std::string url_host(std::string_view address);

// "" when a request with these headers (nullptr: absent) may be served by a server
// bound to `bind`:`port`; else why not, for a 403.
std::string origin_problem(std::string_view bind, int port, const char* host, const char* origin);

// "" when `sent` (nullptr: absent) is `token`, compared in constant time; else why not.
std::string token_problem(std::string_view token, const char* sent);

}  // namespace afhub::viewer

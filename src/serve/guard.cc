#include "serve/guard.h"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>

#include <algorithm>
#include <cctype>

#include "util/printable.h"

namespace weaver::serve {
namespace {

// Splits "name:port" ("[v6]:port" for IPv6); false when the port is not
// a number.  No port: *port is 80, HTTP's default.
bool split_host(const std::string& host, std::string* name, int* port) {
  const size_t close = host.rfind(']');
  const size_t colon = host.rfind(':');
  const bool has_port = colon != std::string::npos && (close == std::string::npos || colon > close);
  *name = lower_ascii(has_port ? host.substr(0, colon) : host);
  *port = 80;
  if (!has_port) return true;
  const std::string digits = host.substr(colon + 1);
  if (digits.empty() || digits.size() > 5) return false;
  for (const char c : digits) {
    if (c < '0' || c > '9') return false;
  }
  *port = std::stoi(digits);
  return true;
}

// The IPv4 addresses of this machine's interfaces.
void interface_addresses(std::vector<std::string>* out) {
  ifaddrs* all = nullptr;
  if (::getifaddrs(&all) != 0) return;
  for (const ifaddrs* i = all; i != nullptr; i = i->ifa_next) {
    if (i->ifa_addr == nullptr || i->ifa_addr->sa_family != AF_INET) continue;
    char ip[INET_ADDRSTRLEN];
    const auto* a = reinterpret_cast<const sockaddr_in*>(i->ifa_addr);
    if (::inet_ntop(AF_INET, &a->sin_addr, ip, sizeof ip) != nullptr) out->push_back(ip);
  }
  ::freeifaddrs(all);
}

}  // namespace

CallerPolicy caller_policy(const std::string& bind, int port,
                           const std::vector<std::string>& allowed) {
  CallerPolicy p;
  p.port = port;
  p.hosts = {"localhost", "127.0.0.1", "[::1]"};
  if (bind == "0.0.0.0") {
    interface_addresses(&p.hosts);
  } else {
    p.hosts.push_back(bind);
  }
  for (const std::string& a : allowed) p.hosts.push_back(lower_ascii(a));
  return p;
}

int check_caller(const Request& r, const CallerPolicy& p, std::string* why) {
  const std::string* host = r.header("host");
  if (host != nullptr) {
    std::string name;
    int port = 0;
    const bool known = split_host(*host, &name, &port) && port == p.port &&
                       std::find(p.hosts.begin(), p.hosts.end(), name) != p.hosts.end();
    if (!known) {
      *why = "Host '" + printable(*host, 80) +
             "' is not this server (weaver serve --allow-host NAME adds a name)";
      return 421;
    }
  }
  const std::string* site = r.header("sec-fetch-site");
  if (site != nullptr && *site != "same-origin" && *site != "none") {
    *why = "a request from another site (Sec-Fetch-Site: " + printable(*site, 40) + ")";
    return 403;
  }
  const std::string* origin = r.header("origin");
  if (origin != nullptr &&
      (host == nullptr || lower_ascii(*origin) != "http://" + lower_ascii(*host))) {
    *why = "a request from another origin (Origin: " + printable(*origin, 80) + ")";
    return 403;
  }
  return 0;
}

}  // namespace weaver::serve

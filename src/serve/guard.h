// Who may call `weaver serve`: the user's own programs and the server's own
// page, not any web page the user happens to visit.  A browser sends every
// request a page makes with the Host it was addressed to and, for requests
// a page of another site makes, Origin or Sec-Fetch-Site saying so; so
//   - a Host that is not one of the server's own names (localhost,
//     127.0.0.1, [::1], the bound address, the machine's interface
//     addresses under --bind 0.0.0.0, or a name given by --allow-host),
//     with the server's port, is 421: a DNS-rebinding page, whose Host is
//     its own name, reads nothing;
//   - Sec-Fetch-Site other than same-origin or none, or an Origin other
//     than the server's own, is 403: a page elsewhere fires nothing (an
//     <img> tag or a form included).
// A request with neither header (curl, Python, the page's own navigation)
// is taken.
#pragma once

#include <string>
#include <vector>

#include "serve/http.h"

namespace weaver::serve {

struct CallerPolicy {
  std::vector<std::string> hosts;  // names, lower case, IPv6 in brackets
  int port = 0;
};

// The policy of a server bound to bind on port, with the names allowed
// besides its own.
CallerPolicy caller_policy(const std::string& bind, int port,
                           const std::vector<std::string>& allowed);

// 0 when r may be answered; else 421 or 403, and *why says which header.
int check_caller(const Request& r, const CallerPolicy& p, std::string* why);

}  // namespace weaver::serve

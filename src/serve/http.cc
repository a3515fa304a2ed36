#include "serve/http.h"

#include <strings.h>

#include <cctype>
#include <cstring>

#include "util/json_string.h"

namespace weaver::serve {
namespace {

const char* reason(int status) {
  switch (status) {
    case 200: return "OK";
    case 400: return "Bad Request";
    case 404: return "Not Found";
    case 405: return "Method Not Allowed";
    case 408: return "Request Timeout";
    case 403: return "Forbidden";
    case 413: return "Content Too Large";
    case 421: return "Misdirected Request";
    case 431: return "Request Header Fields Too Large";
    case 500: return "Internal Server Error";
    case 503: return "Service Unavailable";
    default: return "Error";
  }
}

Status parse_query(const std::string& qs, Request* r) {
  for (size_t from = 0; from <= qs.size();) {
    size_t amp = qs.find('&', from);
    if (amp == std::string::npos) amp = qs.size();
    const std::string pair = qs.substr(from, amp - from);
    const size_t eq = pair.find('=');
    std::string k, v;
    WEAVER_RETURN_IF_ERROR(url_decode(pair.substr(0, eq), &k));
    if (eq != std::string::npos) WEAVER_RETURN_IF_ERROR(url_decode(pair.substr(eq + 1), &v));
    if (!k.empty()) r->query[k] = v;
    from = amp + 1;
  }
  return Status::Ok();
}

// A header name is a token (RFC 9110 5.6.2).
bool is_token_char(unsigned char c) {
  // (strchr finds a NUL too: the string's own end)
  return std::isalnum(c) || (c != 0 && std::strchr("!#$%&'*+-.^_`|~", c) != nullptr);
}

// One header line into r: "name: value", the name a token right before
// the colon, the value without control bytes (tabs aside).
Status parse_header_line(const std::string& h, Request* r) {
  if (h.empty()) return Status::InvalidArgument("malformed header line");
  if (h[0] == ' ' || h[0] == '\t')
    return Status::InvalidArgument("a folded header line (obs-fold)");
  const size_t colon = h.find(':');
  if (colon == std::string::npos || colon == 0) {
    return Status::InvalidArgument("malformed header line");
  }
  for (size_t i = 0; i < colon; ++i) {
    if (!is_token_char(static_cast<unsigned char>(h[i]))) {
      return Status::InvalidArgument("a header name that is not a token (whitespace before ':'?)");
    }
  }
  size_t from = colon + 1, to = h.size();
  while (from < to && (h[from] == ' ' || h[from] == '\t')) ++from;
  while (to > from && (h[to - 1] == ' ' || h[to - 1] == '\t')) --to;
  for (size_t i = from; i < to; ++i) {
    const unsigned char c = static_cast<unsigned char>(h[i]);
    if ((c < 0x20 && c != '\t') || c == 0x7f) {
      return Status::InvalidArgument("a control byte in a header's value");
    }
  }
  r->headers.emplace_back(lower_ascii(h.substr(0, colon)), h.substr(from, to - from));
  return Status::Ok();
}

// Whether a comma-separated list of tokens holds `token` (any case).
bool has_token(const std::string& list, const char* token) {
  size_t from = 0;
  while (from <= list.size()) {
    size_t comma = list.find(',', from);
    if (comma == std::string::npos) comma = list.size();
    size_t a = from, b = comma;
    while (a < b && (list[a] == ' ' || list[a] == '\t')) ++a;
    while (b > a && (list[b - 1] == ' ' || list[b - 1] == '\t')) --b;
    if (::strncasecmp(list.c_str() + a, token, b - a) == 0 && std::strlen(token) == b - a) {
      return true;
    }
    from = comma + 1;
  }
  return false;
}

}  // namespace

std::string lower_ascii(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string response_head(const Response& r, bool keep_alive, Framing framing) {
  std::string head = "HTTP/1.1 " + std::to_string(r.status) + " " + reason(r.status) + "\r\n";
  head += "Content-Type: " + r.content_type + "\r\n";
  if (framing == Framing::kChunked) head += "Transfer-Encoding: chunked\r\n";
  if (framing == Framing::kLength) {
    const uint64_t length = r.file ? r.file->size : r.body.size();
    head += "Content-Length: " + std::to_string(length) + "\r\n";
  }
  if (framing == Framing::kClose) keep_alive = false;
  head += "Cache-Control: " + r.cache_control + "\r\n";
  if (!r.attachment.empty()) {
    head += "Content-Disposition: attachment; filename=\"" + r.attachment + "\"\r\n";
  }
  head += "X-Content-Type-Options: nosniff\r\n";
  for (const auto& [name, value] : r.extra_headers) head += name + ": " + value + "\r\n";
  head += keep_alive ? "Connection: keep-alive\r\n\r\n" : "Connection: close\r\n\r\n";
  return head;
}

bool body_length(const Request& r, uint64_t max_body, uint64_t* length, Response* error) {
  *length = 0;
  if (r.header("transfer-encoding") != nullptr) {
    return *error = error_response(400, "Transfer-Encoding is not taken: send Content-Length"),
           false;
  }
  bool seen = false;
  for (const auto& [name, value] : r.headers) {
    if (name != "content-length") continue;
    uint64_t v = 0;
    bool digits = !value.empty() && value.size() <= 19;
    for (const char c : value) digits = digits && c >= '0' && c <= '9';
    if (digits) v = std::strtoull(value.c_str(), nullptr, 10);
    if (!digits || (seen && v != *length)) {
      return *error = error_response(400, "bad Content-Length"), false;
    }
    *length = v, seen = true;
  }
  if (*length > max_body) {
    return *error = error_response(
               413, "the body is larger than " + std::to_string(max_body >> 20) + " MiB"),
           false;
  }
  return true;
}

Response error_response(int status, const std::string& message) {
  return {status, "application/json", "{\"error\": " + json_string(message) + "}\n"};
}

Status url_decode(const std::string& in, std::string* out) {
  out->clear();
  for (size_t i = 0; i < in.size(); ++i) {
    if (in[i] == '+') {
      *out += ' ';
    } else if (in[i] == '%') {
      if (i + 2 >= in.size() || !std::isxdigit(static_cast<unsigned char>(in[i + 1])) ||
          !std::isxdigit(static_cast<unsigned char>(in[i + 2]))) {
        return Status::InvalidArgument("bad %-escape in '" + in + "'");
      }
      *out += char(std::stoi(in.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      *out += in[i];
    }
  }
  return Status::Ok();
}

Status parse_request_head(const std::string& head, Request* r, bool* too_large) {
  *too_large = false;
  *r = Request{};
  const size_t line_end = std::min(head.find("\r\n"), head.size());
  if (line_end > kMaxRequestLine) {
    *too_large = true;
    return Status::InvalidArgument("the request line is longer than 8 KiB");
  }
  if (head.size() - line_end > kMaxHeaders) {
    *too_large = true;
    return Status::InvalidArgument("the headers are longer than 32 KiB");
  }
  const std::string line = head.substr(0, line_end);
  // METHOD SP TARGET SP VERSION: a method of capitals, a target without
  // spaces or control bytes.
  const size_t sp1 = line.find(' '), sp2 = line.rfind(' ');
  if (sp1 == 0 || sp1 == std::string::npos || sp2 <= sp1 + 1) {
    return Status::InvalidArgument("malformed request line");
  }
  r->method = line.substr(0, sp1);
  const std::string target = line.substr(sp1 + 1, sp2 - sp1 - 1);
  for (const char c : r->method) {
    if (c < 'A' || c > 'Z') return Status::InvalidArgument("malformed request method");
  }
  for (const char c : target) {
    if (static_cast<unsigned char>(c) <= 0x20 || c == 0x7f) {
      return Status::InvalidArgument("malformed request target");
    }
  }
  const std::string version = line.substr(sp2 + 1);
  if (version != "HTTP/1.1" && version != "HTTP/1.0") {
    return Status::InvalidArgument("not HTTP/1.0 or HTTP/1.1");
  }
  if (target.empty() || target[0] != '/') {
    return Status::InvalidArgument("the target is not a path");
  }
  const size_t q = target.find('?');
  WEAVER_RETURN_IF_ERROR(url_decode(target.substr(0, q), &r->path));
  if (q != std::string::npos) WEAVER_RETURN_IF_ERROR(parse_query(target.substr(q + 1), r));
  for (size_t at = line_end; at < head.size();) {
    size_t next = head.find("\r\n", at + 2);
    if (next == std::string::npos) next = head.size();
    WEAVER_RETURN_IF_ERROR(parse_header_line(head.substr(at + 2, next - at - 2), r));
    at = next;
  }
  r->http10 = version == "HTTP/1.0";
  if (!r->http10 && r->header_count("host") != 1) {
    return Status::InvalidArgument("an HTTP/1.1 request has one Host header");
  }
  bool close = false, keep = false;
  for (const auto& [name, value] : r->headers) {
    if (name != "connection") continue;
    close = close || has_token(value, "close");
    keep = keep || has_token(value, "keep-alive");
  }
  r->keep_alive = !close && (!r->http10 || keep);
  return Status::Ok();
}

}  // namespace weaver::serve

#include "serve/http.h"

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
    case 413: return "Payload Too Large";
    case 431: return "Request Header Fields Too Large";
    case 500: return "Internal Server Error";
    case 503: return "Service Unavailable";
    default: return "Error";
  }
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
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

}  // namespace

std::string response_head(const Response& r, bool keep_alive, bool chunked) {
  std::string head = "HTTP/1.1 " + std::to_string(r.status) + " " + reason(r.status) + "\r\n";
  head += "Content-Type: " + r.content_type + "\r\n";
  head += chunked ? std::string("Transfer-Encoding: chunked\r\n")
                  : "Content-Length: " + std::to_string(r.body.size()) + "\r\n";
  head += "Cache-Control: " + r.cache_control + "\r\n";
  if (!r.attachment.empty()) {
    head += "Content-Disposition: attachment; filename=\"" + r.attachment + "\"\r\n";
  }
  head += "X-Content-Type-Options: nosniff\r\n";
  head += keep_alive ? "Connection: keep-alive\r\n\r\n" : "Connection: close\r\n\r\n";
  return head;
}

bool body_length(const Request& r, uint64_t max_body, uint64_t* length, Response* error) {
  *length = 0;
  const auto cl = r.headers.find("content-length");
  if (cl != r.headers.end()) {
    char* end = nullptr;
    *length = std::strtoull(cl->second.c_str(), &end, 10);
    if (cl->second.empty() || *end != '\0' || !std::isdigit(uint8_t(cl->second[0]))) {
      return *error = error_response(400, "bad Content-Length"), false;
    }
  }
  if (r.headers.count("transfer-encoding")) {
    return *error = error_response(400, "chunked bodies are not taken: send Content-Length"), false;
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
    const std::string h = head.substr(at + 2, next - at - 2);
    const size_t colon = h.find(':');
    if (colon == std::string::npos || colon == 0) {
      return Status::InvalidArgument("malformed header line");
    }
    size_t v = colon + 1;
    while (v < h.size() && (h[v] == ' ' || h[v] == '\t')) ++v;
    r->headers[lower(h.substr(0, colon))] = h.substr(v);
    at = next;
  }
  const auto c = r->headers.find("connection");
  const std::string connection = c == r->headers.end() ? "" : lower(c->second);
  r->keep_alive = version == "HTTP/1.1" ? connection != "close" : connection == "keep-alive";
  return Status::Ok();
}

}  // namespace weaver::serve

#include "serve/params.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "util/printable.h"

namespace weaver::serve {

bool parse_finite(const std::string& s, double* v) {
  if (s.empty() || s.size() > 64) return false;
  for (const char c : s) {
    const bool ok =
        (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || c == 'e' || c == 'E';
    if (!ok) return false;
  }
  char* end = nullptr;
  *v = std::strtod(s.c_str(), &end);
  return *end == '\0' && std::isfinite(*v);
}

bool parse_whole(const std::string& s, uint64_t lo, uint64_t hi, uint64_t* v) {
  if (s.empty() || s.size() > 20) return false;
  for (const char c : s) {
    if (c < '0' || c > '9') return false;
  }
  errno = 0;
  char* end = nullptr;
  const unsigned long long n = std::strtoull(s.c_str(), &end, 10);
  if (errno == ERANGE || *end != '\0' || n < lo || n > hi) return false;
  *v = n;
  return true;
}

std::string quoted(const std::string& s) { return "'" + printable(s, 40) + "'"; }

Status Params::number(const char* name, bool required, double* v) const {
  const std::string* s = value(name);
  if (s == nullptr) {
    return required ? Status::InvalidArgument(std::string(name) + " is required") : Status::Ok();
  }
  if (!parse_finite(*s, v)) {
    return Status::InvalidArgument(std::string(name) + "=" + quoted(*s) + " is not a number");
  }
  return Status::Ok();
}

Status Params::whole(const char* name, uint64_t lo, uint64_t hi, bool required, uint64_t* v) const {
  const std::string* s = value(name);
  if (s == nullptr) {
    return required ? Status::InvalidArgument(std::string(name) + " is required") : Status::Ok();
  }
  if (!parse_whole(*s, lo, hi, v)) {
    return Status::InvalidArgument(std::string(name) + "=" + quoted(*s) +
                                   " is not a whole number from " + std::to_string(lo) + " to " +
                                   std::to_string(hi));
  }
  return Status::Ok();
}

Status Params::flag(const char* name, bool* v) const {
  const std::string* s = value(name);
  *v = false;
  if (s == nullptr || *s == "0") return Status::Ok();
  if (*s == "1") return *v = true, Status::Ok();
  return Status::InvalidArgument(std::string(name) + "=" + quoted(*s) + " is not 0 or 1");
}

Status Params::choice(const char* name, std::initializer_list<const char*> names, int* v) const {
  const std::string* s = value(name);
  if (s == nullptr) return Status::Ok();
  std::string list;
  int i = 0;
  for (const char* n : names) {
    if (*s == n) return *v = i, Status::Ok();
    list += std::string(i++ ? ", " : "") + n;
  }
  return Status::InvalidArgument(std::string(name) + "=" + quoted(*s) + " is not one of " + list);
}

Status Params::box(const char* name, double v[6]) const {
  const std::string* s = value(name);
  const std::string usage = std::string(name) + " is six numbers: X0,Y0,Z0,X1,Y1,Z1";
  if (s == nullptr) return Status::InvalidArgument(usage);
  size_t from = 0;
  for (int i = 0; i < 6; ++i) {
    const size_t comma = i < 5 ? s->find(',', from) : s->size();
    if (comma == std::string::npos || !parse_finite(s->substr(from, comma - from), &v[i])) {
      return Status::InvalidArgument(usage);
    }
    from = comma + 1;
  }
  return Status::Ok();
}

}  // namespace weaver::serve

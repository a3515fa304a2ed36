// The values of a request's path and query string, parsed and bounded
// before any reaches the query engine: numbers as finite doubles, ids and
// ticks as whole numbers in a range, switches as 0 or 1, names from fixed
// lists.  A value that is not one of these is InvalidArgument (400), and
// the message quotes at most the first few bytes of what was sent.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <string>

#include "schema/status.h"
#include "serve/http.h"

namespace weaver::serve {

// A finite number, as C's strtod reads it from digits, a sign, a point and
// an exponent only (no "inf", "nan", hex or spaces).
bool parse_finite(const std::string& s, double* v);
// Digits only, within [lo, hi].
bool parse_whole(const std::string& s, uint64_t lo, uint64_t hi, uint64_t* v);

// What a client sent, fit to quote in an error: at most 40 bytes.
std::string quoted(const std::string& s);

class Params {
 public:
  explicit Params(const Request& r) : r_(r) {}
  bool has(const char* name) const { return r_.query.count(name) != 0; }
  // Each: *v from the parameter; absent, a required one is an error and an
  // optional one leaves *v as it was.
  Status number(const char* name, bool required, double* v) const;
  Status whole(const char* name, uint64_t lo, uint64_t hi, bool required, uint64_t* v) const;
  // 0 or 1 (absent: false).
  Status flag(const char* name, bool* v) const;
  // One of names, as its index (absent: *v as it was).
  Status choice(const char* name, std::initializer_list<const char*> names, int* v) const;
  // "X0,Y0,Z0,X1,Y1,Z1": six finite numbers.
  Status box(const char* name, double v[6]) const;

 private:
  const std::string* value(const char* name) const {
    const auto it = r_.query.find(name);
    return it == r_.query.end() ? nullptr : &it->second;
  }
  const Request& r_;
};

}  // namespace weaver::serve

#include "util/args.h"

#include <unistd.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>

namespace weaver {

uint64_t physical_memory() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) : 0;
}

Status parse_args(int argc, char** argv, int start, const std::set<std::string>& value_options,
                  const std::set<std::string>& flag_options, ParsedArgs* out) {
  for (int i = start; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      out->help = true;
    } else if (a.rfind("--", 0) == 0) {
      const std::string name = a.substr(2);
      if (out->has(name)) return Status::InvalidArgument("option " + a + " given twice");
      if (value_options.count(name)) {
        if (i + 1 >= argc) return Status::InvalidArgument("option " + a + " needs a value");
        out->values[name] = argv[++i];
      } else if (flag_options.count(name)) {
        out->flags.insert(name);
      } else {
        return Status::InvalidArgument("unknown option " + a);
      }
    } else {
      out->positional.push_back(a);
    }
  }
  return Status::Ok();
}

Status parse_u64(const std::string& text, const std::string& what, uint64_t* out) {
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), *out);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size()) {
    return Status::InvalidArgument(what + " must be a non-negative integer, got '" + text + "'");
  }
  return Status::Ok();
}

Status parse_double(const std::string& text, const std::string& what, double* out) {
  char* end = nullptr;
  *out = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(*out)) {
    return Status::InvalidArgument(what + " must be a number, got '" + text + "'");
  }
  return Status::Ok();
}

namespace {

// A number with an optional K/M/G/T suffix in powers of `base`; `extra`
// letters may end the suffix ("B", "iB" for sizes).  The result must be
// below 2^64: anything larger would wrap.
Status parse_scaled(const std::string& text, const std::string& what, double base, bool bytes,
                    const char* like, uint64_t* out) {
  size_t digits = 0;
  while (digits < text.size() &&
         (std::isdigit(static_cast<unsigned char>(text[digits])) || text[digits] == '.')) {
    ++digits;
  }
  std::string unit = text.substr(digits);
  for (char& c : unit) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (bytes && unit.size() > 1 && unit.back() == 'B') unit.pop_back();
  if (bytes && unit.size() > 1 && unit.back() == 'I') unit.pop_back();
  const std::string letters = bytes ? "BKMGT" : " KMGT";
  const size_t power = unit.size() == 1 ? letters.find(unit[0]) : std::string::npos;
  const double scale = unit.empty()                 ? 1
                       : power == std::string::npos ? 0
                                                    : std::pow(base, double(power));
  double value = 0;
  if (digits == 0 || scale == 0 || !parse_double(text.substr(0, digits), what, &value).ok()) {
    return Status::InvalidArgument(what + " must be " + like + ", got '" + text + "'");
  }
  // 2^64 is exactly representable; anything at or above it would wrap.
  if (!(value * scale < 18446744073709551616.0)) {
    return Status::InvalidArgument(what + " is too large: '" + text + "'");
  }
  *out = static_cast<uint64_t>(value * scale);
  return Status::Ok();
}

}  // namespace

Status parse_bytes(const std::string& text, const std::string& what, uint64_t* out) {
  return parse_scaled(text, what, 1024, true, "a size like 256M or 2G", out);
}

Status parse_count(const std::string& text, const std::string& what, uint64_t* out) {
  return parse_scaled(text, what, 1000, false, "a count like 5000000 or 5G", out);
}

namespace {
std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (true) {
    const size_t c = text.find(',', start);
    parts.push_back(text.substr(start, c == std::string::npos ? std::string::npos : c - start));
    if (c == std::string::npos) return parts;
    start = c + 1;
  }
}
}  // namespace

template <typename T>
Status parse_list(const std::string& text, const std::string& what, size_t n, std::vector<T>* out,
                  Status (*parse_one)(const std::string&, const std::string&, T*)) {
  const auto parts = split(text);
  if (parts.size() != n) {
    return Status::InvalidArgument(what + " needs " + std::to_string(n) +
                                   " comma-separated values, got '" + text + "'");
  }
  out->resize(n);
  for (size_t i = 0; i < n; ++i) WEAVER_RETURN_IF_ERROR(parse_one(parts[i], what, &(*out)[i]));
  return Status::Ok();
}

Status parse_u64_list(const std::string& text, const std::string& what, size_t n,
                      std::vector<uint64_t>* out) {
  return parse_list(text, what, n, out, &parse_u64);
}

Status parse_double_list(const std::string& text, const std::string& what, size_t n,
                         std::vector<double>* out) {
  return parse_list(text, what, n, out, &parse_double);
}

}  // namespace weaver

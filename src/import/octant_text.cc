#include "import/octant_text.h"

#include <cerrno>
#include <charconv>
#include <cstring>
#include <memory>

#include "util/printable.h"

namespace weaver {
namespace {

constexpr size_t kReadChunk = 1 << 20;

std::string shorten(std::string_view s) { return printable(s); }

// Parses one non-comment line; returns "" on success or the reason it failed.
std::string parse_line(std::string_view line, Octant* o) {
  int64_t v[4];
  int fields = 0;
  size_t i = 0;
  while (true) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    if (i == line.size()) break;
    if (fields == 4)
      return "expected 4 integers 'x y z level', found more: '" + shorten(line) + "'";
    const char* begin = line.data() + i;
    const auto [ptr, ec] = std::from_chars(begin, line.data() + line.size(), v[fields]);
    const bool ends_field = ptr == line.data() + line.size() || *ptr == ' ' || *ptr == '\t';
    if (ec == std::errc::result_out_of_range) return "number out of range: '" + shorten(line) + "'";
    if (ec != std::errc() || !ends_field) {
      return "expected 4 integers 'x y z level', found '" + shorten(line) + "'";
    }
    ++fields;
    i = static_cast<size_t>(ptr - line.data());
  }
  if (fields != 4) return "expected 4 integers 'x y z level', found '" + shorten(line) + "'";
  if (v[3] < 0 || v[3] > kMaxLevel) {
    return "level " + std::to_string(v[3]) + " out of range [0, 20]";
  }
  for (int a = 0; a < 3; ++a) {
    if (v[a] < 0 || v[a] >= int64_t{kRootEdge}) {
      return "coordinate " + std::to_string(v[a]) + " out of range [0, 1048576)";
    }
  }
  *o = {uint32_t(v[0]), uint32_t(v[1]), uint32_t(v[2]), uint8_t(v[3])};
  if (!octant_is_valid(*o)) {
    return "corner (" + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " +
           std::to_string(v[2]) + ") is not a multiple of the edge " +
           std::to_string(octant_edge(o->level)) + " of level " + std::to_string(v[3]);
  }
  return "";
}

bool is_blank_or_comment(std::string_view line) {
  size_t i = 0;
  while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
  return i == line.size() || line[i] == '#';
}

}  // namespace

Status read_octant_text(const std::string& path,
                        const std::function<Status(const Octant&, uint64_t)>& on_octant) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) return Status::IOError("cannot open " + path + ": " + std::strerror(errno));
  std::string carry;  // a partial line from the previous chunk
  // Not zeroed: fread fills what it reads, and a small file then touches a
  // page of the megabyte, not all of it (tests import thousands of them).
  const auto chunk = std::make_unique_for_overwrite<char[]>(kReadChunk);
  uint64_t line_no = 0;
  auto handle = [&](std::string_view line) -> Status {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (is_blank_or_comment(line)) return Status::Ok();
    Octant o;
    const std::string err = parse_line(line, &o);
    if (!err.empty()) {
      return Status::InvalidArgument(path + ":" + std::to_string(line_no) + ": " + err);
    }
    return on_octant(o, line_no);
  };
  while (true) {
    const size_t got = std::fread(chunk.get(), 1, kReadChunk, f.get());
    if (got == 0) break;
    std::string_view data(chunk.get(), got);
    size_t nl;
    while ((nl = data.find('\n')) != std::string_view::npos) {
      if (!carry.empty()) {
        carry.append(data.substr(0, nl));
        WEAVER_RETURN_IF_ERROR(handle(carry));
        carry.clear();
      } else {
        WEAVER_RETURN_IF_ERROR(handle(data.substr(0, nl)));
      }
      data.remove_prefix(nl + 1);
    }
    carry.append(data);
  }
  if (std::ferror(f.get())) return Status::IOError("cannot read " + path);
  if (!carry.empty()) WEAVER_RETURN_IF_ERROR(handle(carry));
  return Status::Ok();
}

Status write_octant_text(const std::string& path, const std::vector<Octant>& octants,
                         const std::string& header_comment) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "wb"), &std::fclose);
  if (!f) return Status::IOError("cannot create " + path + ": " + std::strerror(errno));
  if (!header_comment.empty()) std::fprintf(f.get(), "# %s\n", header_comment.c_str());
  for (const Octant& o : octants) {
    std::fprintf(f.get(), "%u %u %u %u\n", o.x, o.y, o.z, unsigned{o.level});
  }
  if (std::fflush(f.get()) != 0) return Status::IOError("cannot write " + path);
  return Status::Ok();
}

}  // namespace weaver

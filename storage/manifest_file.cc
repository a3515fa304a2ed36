#include "storage/manifest_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "storage/checksum.h"
#include "storage/crash_point.h"

namespace weaver {
namespace {

std::string hex32(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%08x", v);
  return buf;
}

}  // namespace

Status sync_path(const std::string& path, bool directory) {
  const int fd = ::open(path.c_str(), (directory ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) return Status::IOError("cannot open " + path + ": " + std::strerror(errno));
  const int r = ::fsync(fd);
  ::close(fd);
  if (r != 0) return Status::IOError("cannot sync " + path + ": " + std::strerror(errno));
  return Status::Ok();
}

Status write_manifest_file(const std::string& dir, const std::string& name,
                           const std::string& header, const std::vector<std::string>& lines,
                           bool* renamed) {
  if (renamed != nullptr) *renamed = false;
  std::string body = header + "\n";
  for (const std::string& line : lines) body += line + "\n";
  body += "checksum " + hex32(checksum32(body.data(), body.size())) + "\n";
  const std::string tmp = dir + "/" + name + ".tmp", final_path = dir + "/" + name;
  auto fail = [](const std::string& what, int e) {
    return Status::IOError("cannot " + what + ": " + std::strerror(e));
  };
  if (const int e = crash_point::step()) return fail("write " + tmp, e);
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << body;
    out.flush();
    if (!out) return Status::IOError("cannot write " + tmp);
  }
  if (const int e = crash_point::step()) return fail("sync " + tmp, e);
  WEAVER_RETURN_IF_ERROR(sync_path(tmp, false));
  if (const int e = crash_point::step()) return fail("rename " + tmp, e);
  if (::rename(tmp.c_str(), final_path.c_str()) != 0) return fail("rename " + tmp, errno);
  if (renamed != nullptr) *renamed = true;
  if (const int e = crash_point::step()) return fail("sync " + dir, e);
  return sync_path(dir, true);
}

Status read_manifest_file(const std::string& path, const std::string& header,
                          std::vector<std::string>* lines) {
  lines->clear();
  std::ifstream in(path);
  if (!in) return Status::IOError("cannot read " + path);
  std::string line, body;
  std::getline(in, line);
  if (line != header) return Status::Corruption(path + ": unknown format '" + line + "'");
  body = line + "\n";
  while (std::getline(in, line)) {
    if (line.rfind("checksum ", 0) == 0) {
      if (checksums_enforced() && line.substr(9) != hex32(checksum32(body.data(), body.size()))) {
        return Status::Corruption(path + ": checksum mismatch");
      }
      if (in.peek() != std::char_traits<char>::eof()) {
        return Status::Corruption(path + ": bytes after the checksum line");
      }
      return Status::Ok();
    }
    lines->push_back(line);
    body += line + "\n";
  }
  return Status::Corruption(path + ": truncated (no checksum line)");
}

}  // namespace weaver

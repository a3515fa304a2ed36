#include "model/etree_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <sstream>

namespace weaver {
namespace {

// Do not change: on disk (the etree library's layout).
constexpr uint64_t kEtreeHeaderBytes = 1 + 4 * 4 + 2 * 4 * (kEtreeMaxLevel + 1);  // 273
constexpr uint64_t kBTreeHeaderBytes = 1 + 4 + 8 + 8 + 4 + 4 + 4;                 // 33
constexpr uint32_t kPageHeaderBytes = 25;
constexpr uint32_t kKeyBytes3d = 13;
constexpr uint32_t kPageNumberBytes = 8;
// Sanity bounds on header fields, so that a damaged file cannot ask for
// absurd allocations.
constexpr uint32_t kMaxPageSize = 1u << 24;
constexpr uint32_t kMaxSchemaBytes = 1u << 16;
constexpr uint32_t kMaxAppMetadataBytes = 1u << 24;

bool host_is_little() {
  const uint16_t one = 1;
  unsigned char b;
  std::memcpy(&b, &one, 1);
  return b == 1;
}

uint32_t type_size(const std::string& t) {
  if (t == "int8_t" || t == "uint8_t" || t == "char") return 1;
  if (t == "int16_t" || t == "uint16_t") return 2;
  if (t == "int32_t" || t == "uint32_t" || t == "float32_t" || t == "float") return 4;
  if (t == "int64_t" || t == "uint64_t" || t == "float64_t" || t == "double") return 8;
  return 0;
}

bool same_name(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(a[i])) !=
        std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  }
  return true;
}

}  // namespace

EtreeFile::~EtreeFile() {
  if (fd_ >= 0) ::close(fd_);
}

Status EtreeFile::bad(const std::string& why) const {
  return Status::Corruption(path_ + ": " + why);
}

// An unsigned integer of `bytes` bytes in the file's byte order.
uint64_t EtreeFile::unsigned_at(const std::byte* p, int bytes) const {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) {
    const int at = info_.byte_order == 'L' ? i : bytes - 1 - i;
    v |= uint64_t{static_cast<unsigned char>(p[at])} << (8 * i);
  }
  return v;
}

Status EtreeFile::open(const std::string& path, std::unique_ptr<EtreeFile>* out) {
  std::unique_ptr<EtreeFile> f(new EtreeFile(path));
  f->fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (f->fd_ < 0)
    return Status::NotFound(path + ": cannot open the etree file: " + strerror(errno));
  struct stat st;
  if (fstat(f->fd_, &st) != 0) return Status::IOError(path + ": " + strerror(errno));
  f->file_bytes_ = static_cast<uint64_t>(st.st_size);
  WEAVER_RETURN_IF_ERROR(f->read_headers());
  *out = std::move(f);
  return Status::Ok();
}

Status EtreeFile::read_headers() {
  std::vector<std::byte> h(kEtreeHeaderBytes + kBTreeHeaderBytes);
  if (file_bytes_ < h.size()) return bad("too short for an etree file");
  if (::pread(fd_, h.data(), h.size(), 0) != static_cast<ssize_t>(h.size())) {
    return Status::IOError(path_ + ": cannot read the etree header");
  }
  info_.byte_order = static_cast<char>(h[0]);
  if (info_.byte_order != 'L' && info_.byte_order != 'B') {
    return bad("not an etree file (its first byte is not 'L' or 'B')");
  }
  if (u32(&h[1]) != 1) return bad("etree format version " + std::to_string(u32(&h[1])) + ", not 1");
  const uint32_t dims = u32(&h[5]);
  if (dims != 3)
    return bad(std::to_string(dims) + "-D etree; only 3-D etrees hold velocity models");
  const uint32_t meta_bytes = u32(&h[13]);
  if (meta_bytes > kMaxAppMetadataBytes) return bad("implausible application metadata size");
  for (int l = 0; l <= kEtreeMaxLevel; ++l) {
    info_.leaves += u32(&h[17 + 8 * l]);
    info_.interiors += u32(&h[17 + 8 * l + 4]);
  }
  const std::byte* b = &h[kEtreeHeaderBytes];
  if (static_cast<char>(b[0]) != info_.byte_order) return bad("B-tree header byte order differs");
  info_.page_size = u32(b + 1);
  info_.page_count = u64(b + 5);
  info_.root_page = u64(b + 13);
  info_.key_size = u32(b + 21);
  info_.value_size = u32(b + 25);
  const uint32_t schema_bytes = u32(b + 29);
  if (info_.key_size != kKeyBytes3d) return bad("key size " + std::to_string(info_.key_size));
  if (info_.page_size < 512 || info_.page_size > kMaxPageSize) return bad("implausible page size");
  if (schema_bytes == 0) return bad("no schema: the payload's fields are not named");
  if (schema_bytes > kMaxSchemaBytes) return bad("implausible schema size");
  const uint64_t pages_end = (info_.root_page + info_.page_count) * info_.page_size;
  const uint64_t data_start = kEtreeHeaderBytes + kBTreeHeaderBytes + schema_bytes;
  if (info_.page_count == 0) return bad("the etree is empty");
  if (info_.root_page * info_.page_size < data_start || pages_end + meta_bytes > file_bytes_ ||
      info_.page_count > file_bytes_ / info_.page_size) {
    return bad("truncated: the header promises " + std::to_string(info_.page_count) +
               " pages and metadata past the end of the file");
  }
  std::string schema(schema_bytes, '\0');
  if (::pread(fd_, schema.data(), schema_bytes, kEtreeHeaderBytes + kBTreeHeaderBytes) !=
      static_cast<ssize_t>(schema_bytes)) {
    return Status::IOError(path_ + ": cannot read the schema");
  }
  schema.resize(strnlen(schema.data(), schema.size()));
  std::istringstream in(schema);
  std::string order;
  int count = -1;
  if (!(in >> order >> count) || (order != "L" && order != "B") || count <= 0 || count > 256) {
    return bad("unreadable schema '" + schema + "'");
  }
  uint32_t end = 0;
  for (int i = 0; i < count; ++i) {
    EtreeField fl;
    if (!(in >> fl.name >> fl.type >> fl.size >> fl.offset))
      return bad("unreadable schema '" + schema + "'");
    if (type_size(fl.type) != fl.size || fl.offset + fl.size > info_.value_size) {
      return bad("schema field '" + fl.name + "' (" + fl.type + ") does not fit the payload");
    }
    end = std::max(end, fl.offset + fl.size);
    info_.fields.push_back(fl);
  }
  const uint32_t entry = info_.key_size + std::max(info_.value_size, kPageNumberBytes);
  if (kPageHeaderBytes + entry > info_.page_size) return bad("records larger than a page");
  if (meta_bytes > 0) {
    info_.app_metadata.assign(meta_bytes, '\0');
    if (::pread(fd_, info_.app_metadata.data(), meta_bytes, pages_end) !=
        static_cast<ssize_t>(meta_bytes)) {
      return Status::IOError(path_ + ": cannot read the application metadata");
    }
    info_.app_metadata.resize(strnlen(info_.app_metadata.data(), meta_bytes));
  }
  return Status::Ok();
}

const EtreeField* EtreeFile::field(const std::string& name) const {
  for (const EtreeField& f : info_.fields) {
    if (same_name(f.name, name)) return &f;
  }
  return nullptr;
}

double EtreeFile::read_field(const std::byte* payload, const EtreeField& f) const {
  unsigned char b[8];
  std::memcpy(b, payload + f.offset, f.size);
  if ((info_.byte_order == 'L') != host_is_little()) {
    for (uint32_t i = 0; i < f.size / 2; ++i) std::swap(b[i], b[f.size - 1 - i]);
  }
  const std::string& t = f.type;
  auto as = [&](auto v) {
    std::memcpy(&v, b, sizeof v);
    return static_cast<double>(v);
  };
  if (t == "float" || t == "float32_t") return as(float{});
  if (t == "double" || t == "float64_t") return as(double{});
  if (t == "int8_t" || t == "char") return as(int8_t{});
  if (t == "uint8_t") return as(uint8_t{});
  if (t == "int16_t") return as(int16_t{});
  if (t == "uint16_t") return as(uint16_t{});
  if (t == "int32_t") return as(int32_t{});
  if (t == "uint32_t") return as(uint32_t{});
  if (t == "int64_t") return as(int64_t{});
  return as(uint64_t{});
}

Status EtreeFile::read_page(uint64_t page_no) {
  if (page_no < info_.root_page || page_no >= info_.root_page + info_.page_count) {
    return bad("page " + std::to_string(page_no) + " is outside the B-tree");
  }
  // Every page is read at most once by a scan; more reads mean a cycle.
  if (++pages_read_ > info_.page_count) return bad("the pages form a cycle");
  page_.resize(info_.page_size);
  const ssize_t got = ::pread(fd_, page_.data(), page_.size(), page_no * info_.page_size);
  if (got != static_cast<ssize_t>(page_.size())) {
    return Status::IOError(path_ + ": cannot read page " + std::to_string(page_no));
  }
  page_no_ = page_no;
  entry_ = 0;
  entries_ = u32(&page_[16]);
  const char type = static_cast<char>(page_[24]);
  const uint32_t size = info_.key_size + (type == 'l' ? info_.value_size : kPageNumberBytes);
  if ((type != 'l' && type != 'i') ||
      uint64_t{entries_} * size > info_.page_size - kPageHeaderBytes) {
    return bad("page " + std::to_string(page_no) + " is damaged (type or entry count)");
  }
  return Status::Ok();
}

Status EtreeFile::start() {
  pages_read_ = 0;
  WEAVER_RETURN_IF_ERROR(read_page(info_.root_page));
  // Down the leftmost children to the first leaf.
  while (static_cast<char>(page_[24]) == 'i') {
    if (entries_ == 0) return bad("index page " + std::to_string(page_no_) + " is empty");
    WEAVER_RETURN_IF_ERROR(read_page(u64(&page_[kPageHeaderBytes + info_.key_size])));
  }
  return Status::Ok();
}

Status EtreeFile::next(EtreeOctant* out, bool* done) {
  while (entry_ == entries_) {
    const uint64_t right = u64(&page_[0]);
    if (right == ~uint64_t{0}) {
      *done = true;
      return Status::Ok();
    }
    WEAVER_RETURN_IF_ERROR(read_page(right));
    if (static_cast<char>(page_[24]) != 'l') {
      return bad("page " + std::to_string(page_no_) + " in the leaf chain is not a leaf");
    }
  }
  const std::byte* e =
      &page_[kPageHeaderBytes + uint64_t{entry_} * (info_.key_size + info_.value_size)];
  ++entry_;
  const unsigned char lead = static_cast<unsigned char>(e[0]);
  out->level = lead & 0x7f;
  out->leaf = (lead & 0x80) != 0;
  if (out->level > kEtreeMaxLevel) {
    return bad("octant of level " + std::to_string(out->level) + " in page " +
               std::to_string(page_no_));
  }
  // The Morton code: bytes 1..12, least significant first.
  uint32_t c[3] = {0, 0, 0};
  for (int bit = 0; bit < 3 * (kEtreeMaxLevel + 1); ++bit) {
    const unsigned byte = static_cast<unsigned char>(e[1 + bit / 8]);
    c[bit % 3] |= uint32_t{(byte >> (bit % 8)) & 1u} << (bit / 3);
  }
  out->x = c[0], out->y = c[1], out->z = c[2];
  out->payload = e + info_.key_size;
  *done = false;
  return Status::Ok();
}

}  // namespace weaver

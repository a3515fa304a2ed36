#include "model/rfile.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <memory>

namespace weaver {
namespace {

// A PROJ string longer than this, or more blocks than this, is a lying
// header, not a model.
constexpr int kMaxProjBytes = 1 << 16;
constexpr int kMaxBlocks = 4096;
constexpr size_t kHeaderRead = 1 << 20;

// Reads the header's fields in turn, byte-swapped where the file says.
class FieldReader {
 public:
  FieldReader(const unsigned char* p, size_t n) : p_(p), n_(n) {}
  bool swap = false;

  bool i32(int32_t* v) { return take(v, 4); }
  bool f64(double* v) { return take(v, 8); }
  bool bytes(size_t len, std::string* s) {
    if (n_ - at_ < len) return false;
    s->assign(reinterpret_cast<const char*>(p_ + at_), len);
    at_ += len;
    return true;
  }
  size_t at() const { return at_; }

 private:
  template <class T>
  bool take(T* v, size_t size) {
    if (n_ - at_ < size) return false;
    unsigned char b[8];
    std::memcpy(b, p_ + at_, size);
    if (swap) {
      for (size_t i = 0; i < size / 2; ++i) std::swap(b[i], b[size - 1 - i]);
    }
    std::memcpy(v, b, size);
    at_ += size;
    return true;
  }
  const unsigned char* p_;
  size_t n_, at_ = 0;
};

bool close_to(double a, double b) { return std::abs(a - b) <= 1e-6 * std::max(1.0, std::abs(a)); }

std::string block_name(size_t b) {
  return b == 0 ? "block 1 (the topography)" : "block " + std::to_string(b + 1);
}

// One block's header against the rules the rest of the file relies on.
Status check_block(const RfileBlock& k, size_t b, const std::string& what) {
  const std::string name = what + ": " + block_name(b);
  for (double v : {k.hh, k.hv}) {
    if (!(v > 0) || !std::isfinite(v) || v > 1e9)
      return Status::Corruption(name + " has a spacing that is not a positive number");
  }
  if (!std::isfinite(k.z0) || std::abs(k.z0) > 1e9)
    return Status::Corruption(name + " has a top (z0) that is not a number");
  if (k.ni < 2 || k.nj < 2)
    return Status::Corruption(name + " has fewer than 2 points along x or y (" +
                              std::to_string(k.ni) + " x " + std::to_string(k.nj) + ")");
  if (b == 0 && (k.nc != 1 || k.nk != 1))
    return Status::Corruption(name + " must have 1 component and 1 level (it has " +
                              std::to_string(k.nc) + " and " + std::to_string(k.nk) + ")");
  if (b > 0 && k.nc != 3 && k.nc != 5)
    return Status::Corruption(name + " has " + std::to_string(k.nc) +
                              " components (3: rho, vp, vs; 5: and qp, qs)");
  if (b > 0 && k.nk < 2)
    return Status::Corruption(name + " has fewer than 2 levels (" + std::to_string(k.nk) + ")");
  return Status::Ok();
}

// What SW4 assumes of the blocks together: one horizontal extent, one
// set of components, stacked top to bottom with no gap between them.
Status check_blocks(const RfileHeader& h, const std::string& what) {
  const RfileBlock& top = h.blocks[0];
  for (size_t b = 1; b < h.blocks.size(); ++b) {
    const RfileBlock& k = h.blocks[b];
    if (!close_to(k.x_extent(), top.x_extent()) || !close_to(k.y_extent(), top.y_extent())) {
      char buf[200];
      std::snprintf(buf, sizeof buf, " spans %g x %g m, block 1 %g x %g m (they must agree)",
                    k.x_extent(), k.y_extent(), top.x_extent(), top.y_extent());
      return Status::Corruption(what + ": " + block_name(b) + buf);
    }
    if (k.nc != h.blocks[1].nc)
      return Status::Corruption(what + ": " + block_name(b) + " has " + std::to_string(k.nc) +
                                " components, block 2 " + std::to_string(h.blocks[1].nc));
    if (b < 2) continue;
    const RfileBlock& above = h.blocks[b - 1];
    if (!(k.z0 > above.z0) || k.z0 > above.bottom() + 1e-6 * std::max(1.0, std::abs(k.z0))) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    " begins at z0 = %g m, but the block above spans %g to %g m (blocks must "
                    "be stacked top to bottom without a gap)",
                    k.z0, above.z0, above.bottom());
      return Status::Corruption(what + ": " + block_name(b) + buf);
    }
  }
  if (h.attenuation != (h.blocks[1].nc == 5))
    return Status::Corruption(what + ": the attenuation flag is " +
                              std::to_string(int(h.attenuation)) + " but the blocks carry " +
                              std::to_string(h.blocks[1].nc) + " components");
  return Status::Ok();
}

}  // namespace

uint64_t RfileHeader::grid_points() const {
  uint64_t n = 0;
  for (size_t b = 1; b < blocks.size(); ++b)
    n += uint64_t(blocks[b].ni) * blocks[b].nj * blocks[b].nk;
  return n;
}

Status parse_rfile_header(const unsigned char* bytes, size_t n, uint64_t file_size,
                          const std::string& what, RfileHeader* h) {
  *h = RfileHeader{};
  FieldReader r(bytes, n);
  const auto truncated = [&](const char* field) {
    return Status::Corruption(what + ": " +
                              (n >= file_size ? std::string("truncated in the header (")
                                              : std::string("a header past 1 MiB (")) +
                              field + ")");
  };
  int32_t magic = 0, precision = 0, attenuation = 0, length = 0, blocks = 0;
  if (!r.i32(&magic)) return truncated("magic");
  if (magic != 1) {
    if (__builtin_bswap32(uint32_t(magic)) != 1)
      return Status::Corruption(what + ": not an rfile (magic " + std::to_string(magic) +
                                ", not 1 in either byte order)");
    r.swap = h->swap = true;
  }
  if (!r.i32(&precision)) return truncated("precision");
  if (precision != 4 && precision != 8)
    return Status::Corruption(what + ": precision " + std::to_string(precision) +
                              " (4 or 8 bytes a value)");
  h->precision = precision;
  if (!r.i32(&attenuation)) return truncated("attenuation");
  if (attenuation != 0 && attenuation != 1)
    return Status::Corruption(what + ": attenuation flag " + std::to_string(attenuation) +
                              " (0 or 1)");
  h->attenuation = attenuation == 1;
  if (!r.f64(&h->azimuth) || !r.f64(&h->lon0) || !r.f64(&h->lat0)) return truncated("origin");
  if (!std::isfinite(h->azimuth) || std::abs(h->azimuth) > 360 || !(std::abs(h->lon0) <= 360) ||
      !(std::abs(h->lat0) <= 90))
    return Status::Corruption(what + ": azimuth, lon0 or lat0 out of range");
  if (!r.i32(&length)) return truncated("PROJ string length");
  if (length < 0 || length > kMaxProjBytes)
    return Status::Corruption(what + ": PROJ string of " + std::to_string(length) + " bytes");
  if (!r.bytes(size_t(length), &h->proj)) return truncated("PROJ string");
  if (!r.i32(&blocks)) return truncated("number of blocks");
  if (blocks < 2 || blocks > kMaxBlocks)
    return Status::Corruption(what + ": " + std::to_string(blocks) +
                              " blocks (the topography and at least one material block)");
  for (int b = 0; b < blocks; ++b) {
    RfileBlock k;
    int32_t dims[4];
    if (!r.f64(&k.hh) || !r.f64(&k.hv) || !r.f64(&k.z0)) return truncated("block spacing");
    for (int32_t& d : dims) {
      if (!r.i32(&d)) return truncated("block dimensions");
    }
    k.nc = dims[0], k.ni = dims[1], k.nj = dims[2], k.nk = dims[3];
    for (int32_t d : dims) {
      if (d <= 0)
        return Status::Corruption(what + ": " + block_name(b) + " has a count " +
                                  std::to_string(d) + " (counts must be positive)");
    }
    WEAVER_RETURN_IF_ERROR(check_block(k, b, what));
    h->blocks.push_back(k);
  }
  uint64_t at = r.at();
  for (size_t b = 0; b < h->blocks.size(); ++b) {
    RfileBlock& k = h->blocks[b];
    k.offset = at;
    // Every count is below 2^31 and there are at most 4096 blocks, so
    // 128 bits hold the sums.
    const unsigned __int128 end = at + static_cast<unsigned __int128>(k.values()) * precision;
    if (end > file_size)
      return Status::Corruption(what + ": " + block_name(b) + " runs past the end of the file (" +
                                std::to_string(file_size) + " bytes)");
    at = static_cast<uint64_t>(end);
  }
  if (at != file_size)
    return Status::Corruption(what + ": " + std::to_string(file_size - at) +
                              " bytes after the last block");
  return check_blocks(*h, what);
}

Status read_rfile_header(const std::string& path, RfileHeader* out) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status::IOError(path + ": " + std::strerror(errno));
  struct stat st;
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return Status::IOError(path + ": not a regular file");
  }
  const size_t n = std::min<uint64_t>(uint64_t(st.st_size), kHeaderRead);
  std::unique_ptr<unsigned char[]> buf(new unsigned char[n + 1]);
  const ssize_t got = ::pread(fd, buf.get(), n, 0);
  ::close(fd);
  if (got != ssize_t(n)) return Status::IOError(path + ": cannot read the header");
  return parse_rfile_header(buf.get(), n, uint64_t(st.st_size), path, out);
}

Status read_rfile_column(int fd, const RfileHeader& h, int b, int i, int j, double* out) {
  return read_rfile_columns(fd, h, b, i, j, 1, out);
}

namespace {

// Bytes [0, n) of the file at `offset`, one pread; IOError if short.
Status read_rfile_bytes(int fd, uint64_t offset, size_t n, unsigned char* out) {
  if (::pread(fd, out, n, off_t(offset)) != ssize_t(n)) {
    return Status::IOError("cannot read the rfile's values");
  }
  return Status::Ok();
}

void to_machine_order(const RfileHeader& h, unsigned char* raw, size_t count) {
  if (!h.swap) return;
  for (size_t v = 0; v < count; ++v) {
    unsigned char* p = raw + v * h.precision;
    for (int a = 0; a < h.precision / 2; ++a) std::swap(p[a], p[h.precision - 1 - a]);
  }
}

// The first value of `count` columns from (i, j) of block b, in values.
uint64_t column_value(const RfileHeader& h, int b, int i, int j) {
  const RfileBlock& k = h.blocks[b];
  return (uint64_t(i) * k.nj + j) * (size_t(k.nk) * k.nc);
}

}  // namespace

void rfile_decode(int precision, const unsigned char* raw, size_t count, double* out) {
  if (precision == 8) {
    std::memcpy(out, raw, count * 8);
    return;
  }
  for (size_t v = 0; v < count; ++v) {
    float f;
    std::memcpy(&f, raw + v * 4, 4);
    out[v] = f;
  }
}

Status read_rfile_raw(int fd, const RfileHeader& h, int b, int i, int j, int count,
                      std::vector<unsigned char>* raw) {
  const RfileBlock& k = h.blocks[b];
  const size_t values = size_t(k.nk) * k.nc * size_t(count);
  raw->resize(values * h.precision);
  WEAVER_RETURN_IF_ERROR(read_rfile_bytes(
      fd, k.offset + column_value(h, b, i, j) * uint64_t(h.precision), raw->size(), raw->data()));
  to_machine_order(h, raw->data(), values);
  return Status::Ok();
}

Status read_rfile_columns(int fd, const RfileHeader& h, int b, int i, int j, int columns,
                          double* out) {
  const RfileBlock& k = h.blocks[b];
  const size_t count = size_t(k.nk) * k.nc * size_t(columns);
  const uint64_t first = column_value(h, b, i, j);
  unsigned char raw[8 * 4096];  // a chunk at a time: no allocation for one column
  for (size_t done = 0; done < count;) {
    const size_t take = std::min(count - done, sizeof raw / size_t(h.precision));
    WEAVER_RETURN_IF_ERROR(read_rfile_bytes(fd, k.offset + (first + done) * uint64_t(h.precision),
                                            take * h.precision, raw));
    to_machine_order(h, raw, take);
    rfile_decode(h.precision, raw, take, out + done);
    done += take;
  }
  return Status::Ok();
}

}  // namespace weaver

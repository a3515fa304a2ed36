// B+tree lifecycle: create, open, header, commit, page allocation.
#include "storage/btree.h"

#include <bit>
#include <cstring>

#include "storage/checksum.h"
#include "storage/shard_set.h"

namespace weaver {
namespace {

Status validate_options(const TableOptions& o, const std::string& name) {
  const uint32_t p = o.page_size;
  if (p < page::kMinPageSize || p > page::kMaxPageSize || !std::has_single_bit(p)) {
    return Status::InvalidArgument(name + ": page size " + std::to_string(p) +
                                   " is not a power of two in [128, 65536]");
  }
  if (page::leaf_capacity(p, o.schema.record_size()) < 2) {
    return Status::InvalidArgument(name + ": records of " + std::to_string(o.schema.record_size()) +
                                   " bytes do not fit two to a page of " + std::to_string(p));
  }
  if (o.packed) {
    page::PackedLeafBuilder one(page::PackedShape::of(p, o.key_kind, o.schema));
    const std::vector<std::byte> widest(o.schema.record_size(), std::byte{0xff});
    const std::vector<std::byte> zero(o.schema.record_size());
    if (!one.add(0, zero.data()) || !one.add(UINT64_MAX, widest.data())) {
      return Status::InvalidArgument(
          name + ": records of " + std::to_string(o.schema.record_size()) +
          " bytes do not fit two to a packed page of " + std::to_string(p));
    }
  }
  const size_t var = o.schema.to_text().size() + o.metadata.size();
  if (!page::file_header_fits(o.schema.to_text().size(), o.metadata.size())) {
    return Status::InvalidArgument(name + ": schema and metadata (" + std::to_string(var) +
                                   " bytes) do not fit in the file header");
  }
  return Status::Ok();
}

}  // namespace

BTree::BTree(std::unique_ptr<File> file, const TableOptions& options, uint64_t pool_bytes)
    : file_(std::move(file)),
      options_(options),
      payload_(options.schema.record_size()),
      leaf_cap_(page::leaf_capacity(options.page_size, payload_)),
      internal_cap_(page::internal_capacity(options.page_size)),
      pool_(std::make_unique<BufferPool>(file_.get(), options.page_size,
                                         pool_bytes - pool_bytes / kDirectoryShare)),
      shape_(page::PackedShape::of(options.page_size, options.key_kind, options.schema)),
      dir_budget_(pool_bytes / kDirectoryShare) {
  if (options.packed) {
    tail_ = std::make_unique<page::PackedLeafBuilder>(shape_);
    edit_ = std::make_unique<page::PackedLeafBuilder>(shape_);
  }
}

BTree::~BTree() { drop_spine(); }

std::string BTree::where(uint32_t page_no) const {
  return file_->name() + ": page " + std::to_string(page_no);
}

Status BTree::create(std::unique_ptr<File> file, const TableOptions& options, uint64_t pool_bytes,
                     std::unique_ptr<BTree>* out) {
  WEAVER_RETURN_IF_ERROR(validate_options(options, file->name()));
  std::unique_ptr<BTree> t(new BTree(std::move(file), options, pool_bytes));
  WEAVER_RETURN_IF_ERROR(t->write_header());
  *out = std::move(t);
  return Status::Ok();
}

Status BTree::open(std::unique_ptr<File> file, uint64_t pool_bytes, std::unique_ptr<BTree>* out) {
  const std::string name = file->name();
  uint64_t size = 0;
  WEAVER_RETURN_IF_ERROR(file->size(&size));
  if (size < page::kFileHeaderBytes) {
    return Status::Corruption(name + ": file is truncated (" + std::to_string(size) +
                              " bytes, no complete header)");
  }
  std::byte bytes[page::kFileHeaderBytes];
  WEAVER_RETURN_IF_ERROR(read_fully(*file, 0, bytes, sizeof bytes));
  page::FileHeader h;
  WEAVER_RETURN_IF_ERROR(page::decode_file_header(bytes, name, &h));
  TableOptions o;
  o.page_size = h.page_size;
  o.key_kind = static_cast<KeyKind>(h.key_kind);
  o.packed = h.leaf_format >= 1;
  std::string error;
  const auto schema = RecordSchema::parse(h.schema_text, &error);
  if (!schema) return Status::Corruption(name + ": bad schema in header: " + error);
  o.schema = *schema;
  o.metadata = std::move(h.metadata);
  if (o.schema.record_size() != h.payload_size) {
    return Status::Corruption(name + ": header payload size disagrees with its schema");
  }
  WEAVER_RETURN_IF_ERROR(validate_options(o, name));
  std::unique_ptr<BTree> t(new BTree(std::move(file), o, pool_bytes));
  t->height_ = h.height;
  t->root_ = h.root;
  t->page_count_ = h.page_count;
  t->free_head_ = h.free_head;
  t->record_count_ = h.record_count;
  if (size < t->file_bytes()) {
    return Status::Corruption(name + ": file is truncated: header lists " +
                              std::to_string(t->page_count_) + " pages, file holds " +
                              std::to_string((size - page::kFileHeaderBytes) / o.page_size));
  }
  if (t->height_ > kMaxHeight || (t->height_ == 0) != (t->root_ == 0) ||
      t->root_ > t->page_count_ || t->free_head_ > t->page_count_) {
    return Status::Corruption(name + ": header fields out of range");
  }
  *out = std::move(t);
  return Status::Ok();
}

Status BTree::write_header() {
  page::FileHeader h;
  h.page_size = options_.page_size;
  h.payload_size = payload_;
  h.key_kind = static_cast<uint8_t>(options_.key_kind);
  h.leaf_format = options_.packed ? 2 : 0;
  h.height = height_;
  h.root = root_;
  h.page_count = page_count_;
  h.free_head = free_head_;
  h.record_count = record_count_;
  h.schema_text = options_.schema.to_text();
  h.metadata = options_.metadata;
  std::byte bytes[page::kFileHeaderBytes];
  page::encode_file_header(h, bytes);
  return write_fully(*file_, 0, bytes, sizeof bytes);
}

Status BTree::sharded_write() const {
  return Status::InvalidArgument(
      file_->name() + ": a sharded table is read-only ('weaver compact' joins its shards)");
}

Status BTree::commit() {
  if (shards_) return sharded_write();
  seal_tail();
  WEAVER_RETURN_IF_ERROR(pool_->flush());
  WEAVER_RETURN_IF_ERROR(write_header());
  return file_->sync();
}

Status BTree::fetch(uint32_t page_no, PageRef* ref, uint32_t prefetch_bytes) {
  if (page_no == 0 || page_no > page_count_) {
    return Status::Corruption(where(page_no) + ": page number out of range (file has " +
                              std::to_string(page_count_) + " pages)");
  }
  Frame* f = nullptr;
  WEAVER_RETURN_IF_ERROR(pool_->fetch(page_no, &f, prefetch_bytes));
  *ref = PageRef(pool_.get(), f);
  return Status::Ok();
}

Status BTree::fetch_typed(uint32_t page_no, page::PageType type, PageRef* ref,
                          uint32_t prefetch_bytes) {
  WEAVER_RETURN_IF_ERROR(fetch(page_no, ref, prefetch_bytes));
  if (page::type(ref->data()) != type) {
    const int found = static_cast<int>(page::type(ref->data()));
    ref->reset();
    return Status::Corruption(where(page_no) + ": expected page type " +
                              std::to_string(static_cast<int>(type)) + ", found " +
                              std::to_string(found));
  }
  // The entry count is trusted by every search of the page: past the
  // capacity it would walk off the page.
  const uint32_t n = page::count(ref->data());
  const uint32_t cap = type == page::PageType::kInternal ? internal_cap_
                       : type == page::PageType::kLeaf
                           ? leaf_cap_
                           : UINT32_MAX;  // packed: PackedLeaf::open checks
  if (n > cap) {
    ref->reset();
    return Status::Corruption(where(page_no) + ": entry count " + std::to_string(n) +
                              " exceeds the page's capacity " + std::to_string(cap));
  }
  return Status::Ok();
}

Status BTree::new_page(page::PageType type, bool at_end, PageRef* ref) {
  uint32_t page_no;
  if (!at_end && free_head_ != 0) {
    PageRef f;
    WEAVER_RETURN_IF_ERROR(fetch_typed(free_head_, page::PageType::kFree, &f));
    page_no = free_head_;
    free_head_ = page::load32(f.data() + page::kPgNextFree);
  } else {
    if (page_count_ == UINT32_MAX) return Status::IOError(file_->name() + ": file is full");
    page_no = ++page_count_;
  }
  Frame* fr = nullptr;
  WEAVER_RETURN_IF_ERROR(pool_->create(page_no, &fr));
  *ref = PageRef(pool_.get(), fr);
  ref->data()[page::kPgType] = static_cast<std::byte>(type);
  return Status::Ok();
}

Status BTree::free_page(uint32_t page_no) {
  Frame* fr = nullptr;
  WEAVER_RETURN_IF_ERROR(pool_->create(page_no, &fr));
  PageRef ref(pool_.get(), fr);
  ref.data()[page::kPgType] = static_cast<std::byte>(page::PageType::kFree);
  page::store32(ref.data() + page::kPgNextFree, free_head_);
  free_head_ = page_no;
  return Status::Ok();
}

}  // namespace weaver

// The file header codec of page_format.h.
#include "storage/page_format.h"

#include "storage/checksum.h"

namespace weaver::page {

bool file_header_fits(size_t schema_bytes, size_t metadata_bytes) {
  return kHdrVarStart + uint64_t{schema_bytes} + metadata_bytes <= kFileHeaderBytes;
}

void encode_file_header(const FileHeader& h, std::byte* out) {
  std::memset(out, 0, kFileHeaderBytes);
  store32(out + kHdrVersion, kFormatVersion);
  std::memcpy(out + kHdrMagic, kMagic, sizeof kMagic);
  store32(out + kHdrPageSize, h.page_size);
  store32(out + kHdrPayloadSize, h.payload_size);
  out[kHdrKeyKind] = static_cast<std::byte>(h.key_kind);
  out[kHdrLeafFormat] = static_cast<std::byte>(h.leaf_format);
  store32(out + kHdrHeight, h.height);
  store32(out + kHdrRoot, h.root);
  store32(out + kHdrPageCount, h.page_count);
  store32(out + kHdrFreeHead, h.free_head);
  store64(out + kHdrRecordCount, h.record_count);
  store32(out + kHdrSchemaLen, static_cast<uint32_t>(h.schema_text.size()));
  store32(out + kHdrMetaLen, static_cast<uint32_t>(h.metadata.size()));
  std::memcpy(out + kHdrVarStart, h.schema_text.data(), h.schema_text.size());
  std::memcpy(out + kHdrVarStart + h.schema_text.size(), h.metadata.data(), h.metadata.size());
  store32(out + kHdrChecksum, checksum32(out + 4, kFileHeaderBytes - 4));
}

Status decode_file_header(const std::byte* in, const std::string& name, FileHeader* h) {
  if (std::memcmp(in + kHdrMagic, kMagic, sizeof kMagic) != 0) {
    return Status::Corruption(name + ": not a weaver B+tree file (bad magic)");
  }
  if (checksums_enforced() &&
      load32(in + kHdrChecksum) != checksum32(in + 4, kFileHeaderBytes - 4)) {
    return Status::Corruption(name + ": header checksum mismatch");
  }
  const uint32_t version = load32(in + kHdrVersion);
  if (version != kFormatVersion) {
    return Status::Corruption(name + ": unsupported format version " + std::to_string(version) +
                              " (this build reads version " + std::to_string(kFormatVersion) + ")");
  }
  h->key_kind = static_cast<uint8_t>(in[kHdrKeyKind]);
  if (h->key_kind > 1) {
    return Status::Corruption(name + ": unknown key kind " + std::to_string(h->key_kind));
  }
  h->leaf_format = static_cast<uint8_t>(in[kHdrLeafFormat]);
  if (h->leaf_format > 2) {
    return Status::Corruption(name + ": unknown leaf format " + std::to_string(h->leaf_format));
  }
  const uint32_t schema_len = load32(in + kHdrSchemaLen);
  const uint32_t meta_len = load32(in + kHdrMetaLen);
  if (!file_header_fits(schema_len, meta_len)) {
    return Status::Corruption(name + ": header schema/metadata lengths out of range");
  }
  h->page_size = load32(in + kHdrPageSize);
  h->payload_size = load32(in + kHdrPayloadSize);
  h->height = load32(in + kHdrHeight);
  h->root = load32(in + kHdrRoot);
  h->page_count = load32(in + kHdrPageCount);
  h->free_head = load32(in + kHdrFreeHead);
  h->record_count = load64(in + kHdrRecordCount);
  const char* var = reinterpret_cast<const char*>(in + kHdrVarStart);
  h->schema_text.assign(var, schema_len);
  h->metadata.assign(var + schema_len, meta_len);
  return Status::Ok();
}

}  // namespace weaver::page

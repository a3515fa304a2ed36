// The Store interface: an ordered map from 64-bit keys to fixed-size payloads,
// implemented by the B+tree (btree.h) and the LSM store (lsm.h).  Keys are
// either node keys (Morton codes) or packed octant keys (schema/octant.h);
// both order as plain unsigned integers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "schema/record_schema.h"
#include "schema/status.h"

namespace weaver {

enum class KeyKind : uint8_t { kNode = 0, kOctant = 1 };  // on disk

struct TableOptions {
  uint32_t page_size = 4096;
  KeyKind key_kind = KeyKind::kOctant;
  RecordSchema schema;   // the payload layout; record_size() is the payload size
  std::string metadata;  // opaque bytes kept with the table (units, origin, ...)
  // Packed leaves (storage/packed_leaf.h): keys delta-coded, payload fields
  // column-wise.  Built by sorted append at about the plain speed; a random
  // put or erase re-packs the leaf it touches.
  bool packed = false;
};

// A forward iterator over (key, payload) in key order.  Not valid across a
// modification of the store it came from.
class Cursor {
 public:
  virtual ~Cursor() = default;
  virtual bool valid() const = 0;
  virtual uint64_t key() const = 0;              // REQUIRES: valid()
  virtual const std::byte* payload() const = 0;  // REQUIRES: valid()
  // Moves to the next record; on an I/O or corruption error the cursor
  // becomes invalid and the error is returned.  REQUIRES: valid()
  virtual Status next() = 0;
};

class Store {
 public:
  virtual ~Store() = default;

  // Sorted append: REQUIRES key greater than every key in the store, else
  // InvalidArgument and the store is unchanged.
  virtual Status append(uint64_t key, const std::byte* payload) = 0;
  // Insert or replace; *replaced (may be null) tells which.
  virtual Status put(uint64_t key, const std::byte* payload, bool* replaced) = 0;
  // NotFound when the key is absent.
  virtual Status erase(uint64_t key) = 0;

  // Exact lookup; payload_out may be null.
  virtual Status get(uint64_t key, std::byte* payload_out, bool* found) = 0;
  // The largest key <= key (the aggregate hit when key is a pixel key).
  virtual Status floor(uint64_t key, uint64_t* key_out, std::byte* payload_out, bool* found) = 0;
  // A cursor at the first key >= key.
  virtual Status seek(uint64_t key, std::unique_ptr<Cursor>* out) = 0;
  // The number of keys < key: the id of `key` when present.
  virtual Status rank(uint64_t key, uint64_t* out) = 0;
  // The record at position index (0-based).  REQUIRES: index < size().
  virtual Status select(uint64_t index, uint64_t* key_out, std::byte* payload_out) = 0;

  virtual uint64_t size() const = 0;
  virtual uint32_t payload_size() const = 0;
  // Makes every change durable (writes back, syncs).
  virtual Status commit() = 0;
};

}  // namespace weaver

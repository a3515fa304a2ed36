// A self-describing layout for fixed-size records: named, typed fields packed
// little-endian in declaration order, with no padding.  A table stores its
// schema as text (schema_to_text) so any reader can find fields by name.
//
// Text form, one field per comma-separated item:   "vp:f32,vs:f32,rho:f32"
// Names are [A-Za-z_][A-Za-z0-9_]*, at most 63 characters; the empty text is
// the schema with no fields (record size 0).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace weaver {

enum class FieldType : uint8_t { kI8, kU8, kI16, kU16, kI32, kU32, kI64, kU64, kF32, kF64 };

uint32_t field_type_size(FieldType t);
std::string_view field_type_name(FieldType t);  // "i8" ... "f64"
std::optional<FieldType> field_type_from_name(std::string_view name);

struct Field {
  std::string name;
  FieldType type;
  uint32_t offset;  // bytes from the start of the record
};

class RecordSchema {
 public:
  RecordSchema() = default;

  // Parses the text form.  On failure returns nullopt and sets *error to a
  // one-line reason.
  static std::optional<RecordSchema> parse(std::string_view text, std::string* error);

  // Appends a field.  Returns false (and sets *error) for a bad or duplicate name.
  bool add_field(std::string_view name, FieldType type, std::string* error);

  std::string to_text() const;
  uint32_t record_size() const { return size_; }
  const std::vector<Field>& fields() const { return fields_; }
  const Field* find(std::string_view name) const;

  // Typed access.  REQUIRES: `record` holds record_size() bytes.
  static double get_double(const std::byte* record, const Field& f);
  static int64_t get_int(const std::byte* record, const Field& f);    // integer fields only
  static uint64_t get_uint(const std::byte* record, const Field& f);  // unsigned fields only
  static void set_double(std::byte* record, const Field& f, double v);
  static void set_int(std::byte* record, const Field& f, int64_t v);

  friend bool operator==(const RecordSchema& a, const RecordSchema& b) {
    return a.to_text() == b.to_text();
  }

 private:
  std::vector<Field> fields_;
  uint32_t size_ = 0;
};

}  // namespace weaver

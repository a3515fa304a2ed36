#include "schema/record_schema.h"

#include <bit>
#include <cstring>

namespace weaver {

static_assert(std::endian::native == std::endian::little,
              "weaver packs records little-endian and supports little-endian hosts only");

namespace {

struct TypeInfo {
  FieldType type;
  std::string_view name;
  uint32_t size;
};

constexpr TypeInfo kTypes[] = {
    {FieldType::kI8, "i8", 1},   {FieldType::kU8, "u8", 1},   {FieldType::kI16, "i16", 2},
    {FieldType::kU16, "u16", 2}, {FieldType::kI32, "i32", 4}, {FieldType::kU32, "u32", 4},
    {FieldType::kI64, "i64", 8}, {FieldType::kU64, "u64", 8}, {FieldType::kF32, "f32", 4},
    {FieldType::kF64, "f64", 8},
};

constexpr size_t kMaxNameLength = 63;

bool name_is_valid(std::string_view name) {
  if (name.empty() || name.size() > kMaxNameLength) return false;
  for (size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    const bool alpha = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
    const bool digit = c >= '0' && c <= '9';
    if (!alpha && !(digit && i > 0)) return false;
  }
  return true;
}

template <typename T>
T load(const std::byte* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

template <typename T>
void store(std::byte* p, T v) {
  std::memcpy(p, &v, sizeof v);
}

}  // namespace

uint32_t field_type_size(FieldType t) { return kTypes[static_cast<int>(t)].size; }
std::string_view field_type_name(FieldType t) { return kTypes[static_cast<int>(t)].name; }

std::optional<FieldType> field_type_from_name(std::string_view name) {
  for (const TypeInfo& info : kTypes) {
    if (info.name == name) return info.type;
  }
  return std::nullopt;
}

bool RecordSchema::add_field(std::string_view name, FieldType type, std::string* error) {
  if (!name_is_valid(name)) {
    *error = "bad field name '" + std::string(name) + "'";
    return false;
  }
  if (find(name) != nullptr) {
    *error = "duplicate field name '" + std::string(name) + "'";
    return false;
  }
  fields_.push_back(Field{std::string(name), type, size_});
  size_ += field_type_size(type);
  return true;
}

std::optional<RecordSchema> RecordSchema::parse(std::string_view text, std::string* error) {
  RecordSchema schema;
  while (!text.empty()) {
    const size_t comma = text.find(',');
    const std::string_view item = text.substr(0, comma);
    const size_t colon = item.find(':');
    if (colon == std::string_view::npos) {
      *error = "schema field '" + std::string(item) + "' is not name:type";
      return std::nullopt;
    }
    const auto type = field_type_from_name(item.substr(colon + 1));
    if (!type) {
      *error = "unknown field type in '" + std::string(item) + "'";
      return std::nullopt;
    }
    if (!schema.add_field(item.substr(0, colon), *type, error)) return std::nullopt;
    if (comma == std::string_view::npos) break;
    text.remove_prefix(comma + 1);
    if (text.empty()) {
      *error = "schema text ends with ','";
      return std::nullopt;
    }
  }
  return schema;
}

std::string RecordSchema::to_text() const {
  std::string out;
  for (const Field& f : fields_) {
    if (!out.empty()) out += ',';
    out += f.name;
    out += ':';
    out += field_type_name(f.type);
  }
  return out;
}

const Field* RecordSchema::find(std::string_view name) const {
  for (const Field& f : fields_) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

int64_t RecordSchema::get_int(const std::byte* record, const Field& f) {
  const std::byte* p = record + f.offset;
  switch (f.type) {
    case FieldType::kI8: return load<int8_t>(p);
    case FieldType::kU8: return load<uint8_t>(p);
    case FieldType::kI16: return load<int16_t>(p);
    case FieldType::kU16: return load<uint16_t>(p);
    case FieldType::kI32: return load<int32_t>(p);
    case FieldType::kU32: return load<uint32_t>(p);
    case FieldType::kI64: return load<int64_t>(p);
    case FieldType::kU64: return static_cast<int64_t>(load<uint64_t>(p));
    case FieldType::kF32: return static_cast<int64_t>(load<float>(p));
    case FieldType::kF64: return static_cast<int64_t>(load<double>(p));
  }
  return 0;
}

uint64_t RecordSchema::get_uint(const std::byte* record, const Field& f) {
  if (f.type == FieldType::kU64) return load<uint64_t>(record + f.offset);
  return static_cast<uint64_t>(get_int(record, f));
}

double RecordSchema::get_double(const std::byte* record, const Field& f) {
  const std::byte* p = record + f.offset;
  if (f.type == FieldType::kF32) return load<float>(p);
  if (f.type == FieldType::kF64) return load<double>(p);
  if (f.type == FieldType::kU64) return static_cast<double>(load<uint64_t>(p));
  return static_cast<double>(get_int(record, f));
}

void RecordSchema::set_int(std::byte* record, const Field& f, int64_t v) {
  std::byte* p = record + f.offset;
  switch (f.type) {
    case FieldType::kI8: store(p, static_cast<int8_t>(v)); break;
    case FieldType::kU8: store(p, static_cast<uint8_t>(v)); break;
    case FieldType::kI16: store(p, static_cast<int16_t>(v)); break;
    case FieldType::kU16: store(p, static_cast<uint16_t>(v)); break;
    case FieldType::kI32: store(p, static_cast<int32_t>(v)); break;
    case FieldType::kU32: store(p, static_cast<uint32_t>(v)); break;
    case FieldType::kI64: store(p, v); break;
    case FieldType::kU64: store(p, static_cast<uint64_t>(v)); break;
    case FieldType::kF32: store(p, static_cast<float>(v)); break;
    case FieldType::kF64: store(p, static_cast<double>(v)); break;
  }
}

void RecordSchema::set_double(std::byte* record, const Field& f, double v) {
  std::byte* p = record + f.offset;
  if (f.type == FieldType::kF32) {
    store(p, static_cast<float>(v));
  } else if (f.type == FieldType::kF64) {
    store(p, v);
  } else {
    set_int(record, f, static_cast<int64_t>(v));
  }
}

}  // namespace weaver

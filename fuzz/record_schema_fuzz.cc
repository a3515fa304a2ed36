// Record schema text ("name:type,..."), stored with every table.
#include <string_view>

#include "schema/record_schema.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string error;
  const auto schema = weaver::RecordSchema::parse(
      std::string_view(reinterpret_cast<const char*>(data), size), &error);
  if (schema) {
    // What it prints it parses back to, field for field.
    const auto again = weaver::RecordSchema::parse(schema->to_text(), &error);
    if (!again || again->to_text() != schema->to_text()) __builtin_trap();
  }
  return 0;
}

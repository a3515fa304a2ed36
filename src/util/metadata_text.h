// A table's metadata text: ";"-separated "key=value" items (units, levels,
// the model, the ground).  The value of one key, "" when absent.
#pragma once

#include <string>

namespace weaver {

inline std::string metadata_item(const std::string& meta, const std::string& key) {
  for (size_t start = 0; start <= meta.size();) {
    size_t end = meta.find(';', start);
    if (end == std::string::npos) end = meta.size();
    if (meta.compare(start, key.size() + 1, key + "=") == 0)
      return meta.substr(start + key.size() + 1, end - start - key.size() - 1);
    start = end + 1;
  }
  return "";
}

}  // namespace weaver

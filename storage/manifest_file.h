// A small text file of lines that commits atomically: a header line, body
// lines, and "checksum <hex>" over everything before it.  Written as
// NAME.tmp, synced, renamed over NAME, and the directory synced; so a crash
// leaves either the old file or the new one, and a torn or altered file is
// caught by the checksum.  The database's MANIFEST and the LSM's run list
// are such files.
#pragma once

#include <string>
#include <vector>

#include "schema/status.h"

namespace weaver {

// *renamed (if given) tells whether the new file took the old one's place:
// after an error it may have (the directory sync failed), and then readers
// see the new contents though they may not survive a power cut.
Status write_manifest_file(const std::string& dir, const std::string& name,
                           const std::string& header, const std::vector<std::string>& lines,
                           bool* renamed = nullptr);
// Reads dir/name back: Corruption for a wrong header, a bad checksum or a
// missing checksum line.
Status read_manifest_file(const std::string& path, const std::string& header,
                          std::vector<std::string>* lines);
// Syncs a file or a directory.
Status sync_path(const std::string& path, bool directory);

}  // namespace weaver

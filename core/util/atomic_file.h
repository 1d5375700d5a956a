// Files we write are written atomically: a crash leaves either the old file or the new one.
#pragma once

#include <string>
#include <string_view>

#include "core/util/expected.h"

namespace selfcal {

// Writes `contents` to `path.tmp.<pid>` in the same folder, fsyncs it, renames it over `path`
// and fsyncs the folder. On error the old file is untouched and the temporary is removed.
Status WriteFileAtomically(const std::string& path, std::string_view contents);

// Makes a completed file durable: fsync of the file, rename to `final_path`, fsync of the folder.
Status CommitFile(const std::string& temporary_path, const std::string& final_path);

// Reads a whole file; the error names the path and the reason.
Expected<std::string> ReadFile(const std::string& path, std::size_t max_bytes = 1u << 30);

}  // namespace selfcal

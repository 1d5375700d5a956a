// Where a result came from: the software, the command line and the input files with a content
// hash, so a result file found on a robot PC months later says what produced it.
#pragma once

#include <string>
#include <vector>

#include "core/util/expected.h"

namespace selfcal::recording {

struct InputFile {
  std::string role;  // "robot", "sensor", "recording"
  std::string path;
  std::string sha256;  // 64 hex digits of the file's content
};

struct Provenance {
  std::string software;      // "selfcal 0.1.0"
  std::string command_line;  // the arguments, shell-quoted where needed
  std::vector<InputFile> inputs;
};

// SHA-256 of a file's content, as 64 lower-case hex digits; an error names the path.
Expected<std::string> FileSha256(const std::string& path);

// This process's command line from /proc/self/cmdline, arguments with spaces or quotes quoted.
std::string ProcessCommandLine();

// Provenance for `inputs` (role, path pairs), hashing each file.
Expected<Provenance> MakeProvenance(const std::string& software,
                                    const std::vector<std::pair<std::string, std::string>>& inputs);

}  // namespace selfcal::recording

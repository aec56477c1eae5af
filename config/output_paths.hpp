#pragma once
// Output-path checks (issue 18, "no silent surprises"): an output file or directory refused
// before any work. Plain functions, no CLI11, so that the tools can call them too; the CLI11
// validators over them are in config/cli_checks.hpp.

#include <string>
#include <vector>

namespace radar_emu::config {

/// Throws std::invalid_argument "PATH: cannot open for writing: ..." unless PATH can be created:
/// its directory exists, is a directory and is writable, PATH itself is not a directory, and
/// (when `extensions` is not empty) its extension is one of them (case-insensitive, with the dot:
/// ".png"). `option` names the option in the message.
void check_output_file(const std::string& path, const std::string& option,
                       const std::vector<std::string>& extensions = {});
/// Throws std::invalid_argument "PATH: cannot create the output directory: ..." unless PATH is a
/// writable directory or can be created (its nearest existing ancestor is a writable directory).
void check_output_dir(const std::string& path, const std::string& option);

}  // namespace radar_emu::config

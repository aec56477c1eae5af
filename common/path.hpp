#pragma once
// File names as every module reads them: the extension that picks a format, whatever its case.

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

namespace radar_emu::common {

/// The extension of `path` with its dot, in lower case (".glb" for "TRUCK.GLB"; "" for none).
[[nodiscard]] inline std::string lower_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace radar_emu::common

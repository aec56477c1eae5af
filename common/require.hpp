#pragma once
// The set-up check of every module's configuration (style.md item 11: fail fast with context).
// For set-up only: it allocates and throws.

#include <stdexcept>
#include <string>
#include <string_view>

namespace radar_emu::common {

/// Throws std::invalid_argument("MODULE: FIELD RULE") unless `ok`, e.g.
/// require(pfa > 0.0 && pfa < 1.0, "cfar", "pfa", "must be in (0, 1)") ->
/// "cfar: pfa must be in (0, 1)".
inline void require(bool ok, std::string_view module, std::string_view field,
                    std::string_view rule) {
  if (!ok) {
    std::string what(module);
    what.append(": ").append(field).append(" ").append(rule);
    throw std::invalid_argument(what);
  }
}

}  // namespace radar_emu::common

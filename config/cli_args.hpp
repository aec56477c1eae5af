#pragma once
// Command-line argument helpers shared by radar-emu's subcommands and the Python module: numbers,
// sweeps and pairs in the form the CLI takes them. Each throws std::invalid_argument naming the
// option, so the caller prints one line.

#include <string_view>
#include <utility>
#include <vector>

namespace radar_emu::config {

/// A finite number (std::from_chars, the whole text). Throws std::invalid_argument
/// "OPTION: 'TEXT' is not a finite number".
[[nodiscard]] double parse_number(std::string_view text, std::string_view option);

/// `text` split at every `sep` (empty fields kept). The views point into `text`.
[[nodiscard]] std::vector<std::string_view> split(std::string_view text, char sep);

/// "X" (one value) or "START:STOP:N" (N >= 1 values, both ends included). Throws
/// std::invalid_argument naming `option` for anything else (non-numbers, N < 1, N > 1e6, NaN).
[[nodiscard]] std::vector<double> parse_sweep(std::string_view text, std::string_view option);

/// "A,B" -> {A, B}, finite numbers; throws std::invalid_argument naming `option`.
[[nodiscard]] std::pair<double, double> parse_pair(std::string_view text, std::string_view option);

}  // namespace radar_emu::config

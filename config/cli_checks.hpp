#pragma once
// Option checks shared by radar-emu's subcommands (issue 18, "no silent surprises"): CLI11
// validators for output paths (checked when the command line is parsed, before any work) and for
// physical ranges (the message in the option's own unit). A failed check is one line,
// "OPTION: what is wrong", printed by main() as "radar-emu: error: ...".

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "config/output_paths.hpp"

namespace radar_emu::config {

/// CLI11 validators over config/output_paths.hpp's two checks.
[[nodiscard]] CLI::Validator output_file(std::vector<std::string> extensions = {});
[[nodiscard]] CLI::Validator output_dir();

/// A number in [lo, hi] (or (lo, hi] / [lo, hi) / (lo, hi) when open_lo / open_hi), refused as
/// "VALUE is outside [LO, HI] UNIT" in the unit the option is given in.
[[nodiscard]] CLI::Validator in_range(double lo, double hi, const std::string& unit,
                                      bool open_lo = false, bool open_hi = false);
/// A sweep "X" or "START:STOP:N" (config/cli_args.hpp parse_sweep) whose every value is in
/// [lo, hi] (open ends as above).
[[nodiscard]] CLI::Validator sweep_in_range(double lo, double hi, const std::string& unit,
                                            bool open_lo = false, bool open_hi = false);

}  // namespace radar_emu::config

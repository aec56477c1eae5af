#include "config/cli_checks.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "common/path.hpp"
#include "config/cli_args.hpp"

namespace radar_emu::config {

namespace fs = std::filesystem;

namespace {

bool writable_directory(const fs::path& dir) {
  std::error_code ec;
  return fs::is_directory(dir, ec) && ::access(dir.c_str(), W_OK | X_OK) == 0;
}

std::string show(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string range_text(double lo, double hi, const std::string& unit, bool open_lo, bool open_hi) {
  return std::string(open_lo ? "(" : "[") + show(lo) + ", " + show(hi) + (open_hi ? ")" : "]") +
         (unit.empty() ? "" : " " + unit);
}

bool inside(double v, double lo, double hi, bool open_lo, bool open_hi) {
  return std::isfinite(v) && (open_lo ? v > lo : v >= lo) && (open_hi ? v < hi : v <= hi);
}

}  // namespace

void check_output_file(const std::string& path, const std::string& option,
                       const std::vector<std::string>& extensions) {
  if (path.empty())
    throw std::invalid_argument(option + ": expected a file name");
  const fs::path p(path);
  if (!extensions.empty()) {
    const std::string ext = common::lower_extension(p);
    if (std::find(extensions.begin(), extensions.end(), ext) == extensions.end()) {
      std::string list;
      for (const std::string& e : extensions)
        list += (list.empty() ? "" : ", ") + e;
      throw std::invalid_argument(path + ": cannot write a '" + ext + "' file (expected " + list +
                                  ")");
    }
  }
  std::error_code ec;
  if (fs::is_directory(p, ec))
    throw std::invalid_argument(path + ": cannot open for writing: it is a directory");
  const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  if (!fs::exists(dir, ec)) {
    throw std::invalid_argument(path + ": cannot open for writing: directory " + dir.string() +
                                " does not exist");
  }
  if (!fs::is_directory(dir, ec)) {
    throw std::invalid_argument(path + ": cannot open for writing: " + dir.string() +
                                " is not a directory");
  }
  if (!writable_directory(dir)) {
    throw std::invalid_argument(path + ": cannot open for writing: directory " + dir.string() +
                                " is not writable");
  }
  if (fs::exists(p, ec) && ::access(p.c_str(), W_OK) != 0)
    throw std::invalid_argument(path + ": cannot open for writing: the file is read-only");
}

void check_output_dir(const std::string& path, const std::string& option) {
  if (path.empty())
    throw std::invalid_argument(option + ": expected a directory");
  std::error_code ec;
  fs::path p = fs::absolute(fs::path(path), ec);
  if (ec)
    p = fs::path(path);
  if (fs::exists(p, ec)) {
    if (!fs::is_directory(p, ec))
      throw std::invalid_argument(path + ": cannot create the output directory: a file is there");
    if (!writable_directory(p))
      throw std::invalid_argument(path + ": cannot create the output directory: not writable");
    return;
  }
  // The nearest existing ancestor must be a writable directory (the rest is created).
  fs::path a = p.parent_path();
  while (!a.empty() && !fs::exists(a, ec) && a != a.parent_path())
    a = a.parent_path();
  if (!fs::is_directory(a, ec)) {
    throw std::invalid_argument(path + ": cannot create the output directory: " + a.string() +
                                " is not a directory");
  }
  if (!writable_directory(a)) {
    throw std::invalid_argument(path + ": cannot create the output directory: " + a.string() +
                                " is not writable");
  }
}

CLI::Validator output_file(std::vector<std::string> extensions) {
  std::string desc = "FILE";
  for (const std::string& e : extensions)
    desc += (desc == "FILE" ? " (" : "|") + e;
  if (!extensions.empty())
    desc += ")";
  return CLI::Validator(
      [extensions](std::string& value) -> std::string {
        try {
          check_output_file(value, "", extensions);
        } catch (const std::invalid_argument& e) {
          return e.what();
        }
        return {};
      },
      desc, "output_file");
}

CLI::Validator output_dir() {
  return CLI::Validator(
      [](std::string& value) -> std::string {
        try {
          check_output_dir(value, "");
        } catch (const std::invalid_argument& e) {
          return e.what();
        }
        return {};
      },
      "DIR", "output_dir");
}

CLI::Validator in_range(double lo, double hi, const std::string& unit, bool open_lo, bool open_hi) {
  const std::string range = range_text(lo, hi, unit, open_lo, open_hi);
  return CLI::Validator(
      [=](std::string& value) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(value, v))
          return "'" + value + "' is not a number";
        if (!inside(v, lo, hi, open_lo, open_hi))
          return value + " is outside " + range;
        return {};
      },
      "in " + range, "in_range");
}

CLI::Validator sweep_in_range(double lo, double hi, const std::string& unit, bool open_lo,
                              bool open_hi) {
  const std::string range = range_text(lo, hi, unit, open_lo, open_hi);
  return CLI::Validator(
      [=](std::string& value) -> std::string {
        try {
          for (double v : parse_sweep(value, "value")) {
            if (!inside(v, lo, hi, open_lo, open_hi))
              return show(v) + (value.find(':') == std::string::npos ? "" : " (in " + value + ")") +
                     " is outside " + range;
          }
        } catch (const std::invalid_argument& e) {
          std::string m = e.what();
          return m.rfind("value: ", 0) == 0 ? m.substr(7) : m;
        }
        return {};
      },
      "in " + range, "sweep_in_range");
}

}  // namespace radar_emu::config

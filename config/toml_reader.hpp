#pragma once
// The one TOML reader of radar-emu: a typed view of one table of a parsed file that knows the
// file's name and the table's path, so that every error is one line in one format:
//
//   FILE: [table] key: what            a key of a table ([radar], [[target]] #2, [scene.target])
//   FILE: key: what                    a key at the top of the file
//   FILE: [table] what                 the table as a whole
//   FILE:LINE:COL: what                a TOML syntax error
//
// What is wrong reads the same everywhere: "expected a number, got a string", "0 is outside
// [1, 1e+08]" (ends as the command-line checks write them: "(" and ")" open, "[" and "]"
// closed), "unknown key (known: a, b)", "unknown value \"x\" (known: a, b)".
//
// Units stay at the edge: a key keeps its unit suffix (azimuth_deg, gain_db) and degrees() and
// decibels() convert it on reading (radians, linear power ratio); ranges are checked in the unit
// of the file. Reads are optional: each returns whether the key was there and leaves `out` (the
// default) as it was when it was not; require() makes a key mandatory. Everything here runs at
// setup; errors throw config::ConfigError (a std::runtime_error). Not real-time safe.

#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace radar_emu::config {

/// Every error of the reader: one line in the format above.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The accepted values of a number: [lo, hi], an end excluded when open (lo < v, v < hi).
/// Non-finite values are always refused.
struct Range {
  double lo = 0.0;
  double hi = 0.0;
  bool open_lo = false;
  bool open_hi = false;
  [[nodiscard]] bool contains(double v) const noexcept;
  /// "[lo, hi]", "(lo, hi]", ... (numbers as std::ostream writes them).
  [[nodiscard]] std::string text() const;
};

/// "FILE: [table] key: what" (table, key or both may be empty; see the top of this header).
[[nodiscard]] std::string error_text(std::string_view file, std::string_view table,
                                     std::string_view key, std::string_view what);
/// Throws ConfigError(error_text(...)): for checks made after reading, in the same format.
[[noreturn]] void fail(std::string_view file, std::string_view table, std::string_view key,
                       std::string_view what);

struct ParsedToml;  // the parsed file (toml++ stays inside config/toml_reader.cpp)

/// A view of one table of a parsed file, or of a table the file does not have (present() is
/// false: every read leaves its default). Cheap to copy; keeps the parsed file alive.
class Table {
 public:
  /// The file as the messages name it, and the table as they show it ("[radar]",
  /// "[[target]] #2"; empty at the top of the file).
  [[nodiscard]] const std::string& file() const noexcept;
  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  [[nodiscard]] bool present() const noexcept { return node_ != nullptr; }
  [[nodiscard]] bool has(std::string_view key) const;

  /// Throws "FILE: [table] key: what".
  [[noreturn]] void fail(std::string_view key, std::string_view what) const;
  /// Refuses the first key not in `known`: "unknown key (known: ...)", or "unknown table (...)"
  /// when its value is a table; the known names are listed in the order given.
  void refuse_unknown(std::span<const std::string_view> known) const;
  void refuse_unknown(std::initializer_list<std::string_view> known) const {
    refuse_unknown(std::span<const std::string_view>(known.begin(), known.size()));
  }
  /// Throws "KEY: is required[ WHY]" unless the key is there (why: " with waypoints_enu_m").
  void require(std::string_view key, std::string_view why = {}) const;

  /// The sub-table `key` (absent: a view that is not present()); "expected a table, got ...".
  [[nodiscard]] Table table(std::string_view key) const;
  /// The array of tables `key` ([[key]]), each named "[[path.key]] #N" with N from 1; an absent
  /// key or an empty array gives none; anything else "expected [[key]] tables, got ...".
  [[nodiscard]] std::vector<Table> tables(std::string_view key) const;

  /// A finite number (TOML integer or float) within `range`.
  bool number(std::string_view key, double& out, Range range) const;
  /// A TOML integer within [lo, hi], stored as Int (the caller's bounds fit Int).
  template <typename Int>
  bool integer(std::string_view key, Int& out, std::int64_t lo, std::int64_t hi) const {
    const std::optional<std::int64_t> v = integer_value(key, lo, hi);
    if (v)
      out = static_cast<Int>(*v);
    return v.has_value();
  }
  bool boolean(std::string_view key, bool& out) const;
  bool string(std::string_view key, std::string& out) const;
  /// A string that is one of `known`: "unknown value \"x\" (known: a, b)".
  bool choice(std::string_view key, std::string& out,
              std::initializer_list<std::string_view> known) const;
  /// Throws "unknown value \"VALUE\" (known: KNOWN)" for a string `key` whose value is not one
  /// of the names listed in `known` ("a, b, c"): for callers whose own parser decides.
  [[noreturn]] void unknown_value(std::string_view key, std::string_view value,
                                  std::string_view known) const;
  /// A number in degrees within `range_deg`, stored in radians (deg x pi / 180).
  bool degrees(std::string_view key, double& out_rad, Range range_deg) const;
  /// A number in dB within `range_db`, stored as a linear power ratio (10^(dB / 10)).
  bool decibels(std::string_view key, double& out_linear, Range range_db) const;
  /// An array of exactly out.size() numbers, each within `each` (element errors name
  /// "key[i]"); out is written only when the whole array is good.
  bool vector(std::string_view key, std::span<double> out, Range each) const;
  /// Three numbers, each within +-limit, into a vector indexed by int (glm::dvec3);
  /// `out` is written only when all three are good.
  template <class Vec3>
  bool vec3(std::string_view key, Vec3& out, double limit) const {
    double v[3] = {0.0, 0.0, 0.0};
    if (!vector(key, v, {-limit, limit}))
      return false;
    for (int i = 0; i < 3; ++i)
      out[i] = v[i];
    return true;
  }
  /// An array of arrays of `length` numbers each within `each` ("key[i][j]"); nullopt if absent.
  [[nodiscard]] std::optional<std::vector<std::vector<double>>> vectors(std::string_view key,
                                                                        std::size_t length,
                                                                        Range each) const;
  /// A number or an array of numbers (any count, no range: the caller checks them with
  /// check()); nullopt if absent.
  [[nodiscard]] std::optional<std::vector<double>> numbers(std::string_view key) const;
  /// Throws the range message for `v` read from `key` unless range.contains(v).
  void check(std::string_view key, double v, Range range) const;

 private:
  friend class TomlFile;
  Table(std::shared_ptr<const ParsedToml> file, const void* node, std::string name,
        std::string dotted);
  [[nodiscard]] const void* get(std::string_view key) const;
  [[nodiscard]] std::optional<std::int64_t> integer_value(std::string_view key, std::int64_t lo,
                                                          std::int64_t hi) const;

  std::shared_ptr<const ParsedToml> file_;
  const void* node_ = nullptr;  ///< the parsed table (toml++), or null when absent
  std::string name_;            ///< "[radar]", "[[target]] #2", "" at the top
  std::string dotted_;          ///< "radar", "scene.target": the path of sub-tables
};

/// A parsed TOML file.
class TomlFile {
 public:
  /// Parses `text`; `file` names it in every message. A syntax error throws ConfigError
  /// "FILE:LINE:COL: what".
  [[nodiscard]] static TomlFile parse(std::string_view text, std::string file);
  /// Reads and parses the file at `path` (named as path.string()); "PATH: cannot open".
  [[nodiscard]] static TomlFile load(const std::filesystem::path& path);
  /// The top of the file.
  [[nodiscard]] Table root() const;

 private:
  explicit TomlFile(std::shared_ptr<const ParsedToml> file) : file_(std::move(file)) {}
  std::shared_ptr<const ParsedToml> file_;
};

}  // namespace radar_emu::config

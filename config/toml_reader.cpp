#include "config/toml_reader.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "common/units.hpp"

namespace radar_emu::config {

struct ParsedToml {
  toml::table root;
  std::string file;
};

namespace {

std::string show(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

const toml::table& as_table(const void* node) {
  return *static_cast<const toml::table*>(node);
}

// "a string", "an integer", ...: what the file holds, for "expected X, got Y".
std::string_view type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a floating-point number";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::date:
      return "a date";
    case toml::node_type::time:
      return "a time";
    case toml::node_type::date_time:
      return "a date-time";
    case toml::node_type::none:
      break;
  }
  return "nothing";
}

std::string expected(std::string_view what, const toml::node& n) {
  return "expected " + std::string(what) + ", got " + std::string(type_name(n));
}

std::string list(std::initializer_list<std::string_view> names) {
  std::string out;
  for (std::string_view n : names)
    out += (out.empty() ? "" : ", ") + std::string(n);
  return out;
}

}  // namespace

bool Range::contains(double v) const noexcept {
  return std::isfinite(v) && (open_lo ? v > lo : v >= lo) && (open_hi ? v < hi : v <= hi);
}

std::string Range::text() const {
  return std::string(open_lo ? "(" : "[") + show(lo) + ", " + show(hi) + (open_hi ? ")" : "]");
}

std::string error_text(std::string_view file, std::string_view table, std::string_view key,
                       std::string_view what) {
  std::string out(file);
  out += ": ";
  if (!table.empty()) {
    out += table;
    out += ' ';
  }
  if (!key.empty()) {
    out += key;
    out += ": ";
  }
  out += what;
  return out;
}

void fail(std::string_view file, std::string_view table, std::string_view key,
          std::string_view what) {
  throw ConfigError(error_text(file, table, key, what));
}

// ---------------------------------------------------------------------------------- TomlFile

TomlFile TomlFile::parse(std::string_view text, std::string file) {
  auto parsed = std::make_shared<ParsedToml>();
  try {
    parsed->root = toml::parse(text, std::string_view(file));
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << file << ':' << e.source().begin.line << ':' << e.source().begin.column << ": "
       << e.description();
    throw ConfigError(os.str());
  }
  parsed->file = std::move(file);
  return TomlFile(std::move(parsed));
}

TomlFile TomlFile::load(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw ConfigError(path.string() + ": cannot open for reading");
  std::ostringstream text;
  text << in.rdbuf();
  return parse(text.str(), path.string());
}

Table TomlFile::root() const {
  return Table(file_, &file_->root, "", "");
}

// ------------------------------------------------------------------------------------- Table

Table::Table(std::shared_ptr<const ParsedToml> file, const void* node, std::string name,
             std::string dotted)
    : file_(std::move(file)), node_(node), name_(std::move(name)), dotted_(std::move(dotted)) {}

const std::string& Table::file() const noexcept {
  return file_->file;
}

const void* Table::get(std::string_view key) const {
  return node_ == nullptr ? nullptr : as_table(node_).get(key);
}

bool Table::has(std::string_view key) const {
  return get(key) != nullptr;
}

void Table::fail(std::string_view key, std::string_view what) const {
  config::fail(file(), name_, key, what);
}

void Table::refuse_unknown(std::span<const std::string_view> known) const {
  if (node_ == nullptr)
    return;
  for (const auto& [key, value] : as_table(node_)) {
    const std::string_view k = key.str();
    bool found = false;
    for (std::string_view n : known)
      found = found || n == k;
    if (found)
      continue;
    std::string names;
    for (std::string_view n : known)
      names += (names.empty() ? "" : ", ") + std::string(n);
    fail(k, std::string(value.is_table() ? "unknown table" : "unknown key") + " (known: " + names +
                ")");
  }
}

void Table::require(std::string_view key, std::string_view why) const {
  if (!has(key))
    fail(key, why.empty() ? std::string("is required") : "is required " + std::string(why));
}

Table Table::table(std::string_view key) const {
  const std::string dotted = dotted_.empty() ? std::string(key) : dotted_ + "." + std::string(key);
  const auto* n = static_cast<const toml::node*>(get(key));
  if (n == nullptr)
    return Table(file_, nullptr, "[" + dotted + "]", dotted);
  const toml::table* t = n->as_table();
  if (t == nullptr)
    fail(key, expected("a table", *n));
  return Table(file_, t, "[" + dotted + "]", dotted);
}

std::vector<Table> Table::tables(std::string_view key) const {
  const std::string dotted = dotted_.empty() ? std::string(key) : dotted_ + "." + std::string(key);
  std::vector<Table> out;
  const auto* n = static_cast<const toml::node*>(get(key));
  if (n == nullptr)
    return out;
  const toml::array* a = n->as_array();
  const std::string want = "[[" + dotted + "]] tables (an array of tables)";
  if (a == nullptr)
    fail(key, expected(want, *n));
  for (const toml::node& e : *a) {
    if (!e.is_table())
      fail(key, expected(want, *n) + " holding " + std::string(type_name(e)));
  }
  for (std::size_t i = 0; i < a->size(); ++i) {
    out.push_back(
        Table(file_, (*a)[i].as_table(), "[[" + dotted + "]] #" + std::to_string(i + 1), dotted));
  }
  return out;
}

void Table::check(std::string_view key, double v, Range range) const {
  if (!range.contains(v))
    fail(key, show(v) + " is outside " + range.text());
}

bool Table::number(std::string_view key, double& out, Range range) const {
  const auto* n = static_cast<const toml::node*>(get(key));
  if (n == nullptr)
    return false;
  const std::optional<double> v = n->value<double>();
  if (!v)
    fail(key, expected("a number", *n));
  check(key, *v, range);
  out = *v;
  return true;
}

std::optional<std::int64_t> Table::integer_value(std::string_view key, std::int64_t lo,
                                                 std::int64_t hi) const {
  const auto* n = static_cast<const toml::node*>(get(key));
  if (n == nullptr)
    return std::nullopt;
  if (!n->is_integer())
    fail(key, expected("an integer", *n));
  const std::int64_t v = *n->value<std::int64_t>();
  if (v < lo || v > hi)
    fail(key, std::to_string(v) + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) +
                  "]");
  return v;
}

bool Table::boolean(std::string_view key, bool& out) const {
  const auto* n = static_cast<const toml::node*>(get(key));
  if (n == nullptr)
    return false;
  if (!n->is_boolean())
    fail(key, expected("true or false", *n));
  out = *n->value<bool>();
  return true;
}

bool Table::string(std::string_view key, std::string& out) const {
  const auto* n = static_cast<const toml::node*>(get(key));
  if (n == nullptr)
    return false;
  if (!n->is_string())
    fail(key, expected("a string", *n));
  out = *n->value<std::string>();
  return true;
}

bool Table::choice(std::string_view key, std::string& out,
                   std::initializer_list<std::string_view> known) const {
  std::string v;
  if (!string(key, v))
    return false;
  bool found = false;
  for (std::string_view k : known)
    found = found || k == v;
  if (!found)
    unknown_value(key, v, list(known));
  out = std::move(v);
  return true;
}

void Table::unknown_value(std::string_view key, std::string_view value,
                          std::string_view known) const {
  fail(key, "unknown value \"" + std::string(value) + "\" (known: " + std::string(known) + ")");
}

bool Table::degrees(std::string_view key, double& out_rad, Range range_deg) const {
  double deg = 0.0;
  if (!number(key, deg, range_deg))
    return false;
  out_rad = common::radians(deg);
  return true;
}

bool Table::decibels(std::string_view key, double& out_linear, Range range_db) const {
  double db = 0.0;
  if (!number(key, db, range_db))
    return false;
  out_linear = common::power_from_db(db);
  return true;
}

namespace {

// The numbers of an array of `length` numbers, each within `each`; `key` names it in errors.
std::vector<double> read_vector(const Table& t, const toml::node& n, const std::string& key,
                                std::size_t length, Range each) {
  const toml::array* a = n.as_array();
  const std::string want = "an array of " + std::to_string(length) + " numbers";
  if (a == nullptr)
    t.fail(key, expected(want, n));
  if (a->size() != length)
    t.fail(key, "expected " + want + ", got an array of " + std::to_string(a->size()));
  std::vector<double> out(length);
  for (std::size_t i = 0; i < length; ++i) {
    const std::string element = key + "[" + std::to_string(i) + "]";
    const std::optional<double> v = (*a)[i].value<double>();
    if (!v)
      t.fail(element, expected("a number", (*a)[i]));
    t.check(element, *v, each);
    out[i] = *v;
  }
  return out;
}

}  // namespace

bool Table::vector(std::string_view key, std::span<double> out, Range each) const {
  const auto* n = static_cast<const toml::node*>(get(key));
  if (n == nullptr)
    return false;
  const std::vector<double> v = read_vector(*this, *n, std::string(key), out.size(), each);
  std::copy(v.begin(), v.end(), out.begin());
  return true;
}

std::optional<std::vector<std::vector<double>>> Table::vectors(std::string_view key,
                                                               std::size_t length,
                                                               Range each) const {
  const auto* n = static_cast<const toml::node*>(get(key));
  if (n == nullptr)
    return std::nullopt;
  const toml::array* a = n->as_array();
  if (a == nullptr)
    fail(key, expected("an array of arrays of " + std::to_string(length) + " numbers", *n));
  std::vector<std::vector<double>> out;
  for (std::size_t i = 0; i < a->size(); ++i) {
    out.push_back(read_vector(*this, (*a)[i], std::string(key) + "[" + std::to_string(i) + "]",
                              length, each));
  }
  return out;
}

std::optional<std::vector<double>> Table::numbers(std::string_view key) const {
  const auto* n = static_cast<const toml::node*>(get(key));
  if (n == nullptr)
    return std::nullopt;
  std::vector<double> out;
  if (const toml::array* a = n->as_array()) {
    for (const toml::node& e : *a) {
      const std::optional<double> v = e.value<double>();
      if (!v) {
        fail(key, expected("a number or an array of numbers", *n) + " holding " +
                      std::string(type_name(e)));
      }
      out.push_back(*v);
    }
  } else if (const std::optional<double> v = n->value<double>()) {
    out.push_back(*v);
  } else {
    fail(key, expected("a number or an array of numbers", *n));
  }
  return out;
}

}  // namespace radar_emu::config

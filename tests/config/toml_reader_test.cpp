// The one TOML reader (config/toml_reader.hpp): every error is one line "FILE: [table] key:
// what"; ranges with open and closed ends; degrees and dB converted on reading; arrays of
// tables; wrong types named; unknown keys refused with the known ones listed.

#include "config/toml_reader.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <string>

namespace config = radar_emu::config;
using config::Range;
using config::Table;
using config::TomlFile;

namespace {

// The message of whatever `read` throws (a ConfigError), or "" when it does not.
template <typename F>
std::string error_of(F&& read) {
  try {
    read();
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

Table root_of(const char* text) {
  return TomlFile::parse(text, "t.toml").root();
}

}  // namespace

TEST(TomlReader, UnknownKeysAreRefusedListingTheKnownOnes) {
  const Table radar = root_of("[radar]\ncarrier_hz = 1e9\ncarrier = 2\n").table("radar");
  EXPECT_EQ(error_of([&] {
              radar.refuse_unknown({"carrier_hz", "prf_hz"});
            }),
            "t.toml: [radar] carrier: unknown key (known: carrier_hz, prf_hz)");
  EXPECT_EQ(error_of([&] { radar.refuse_unknown({"carrier_hz", "carrier"}); }), "");
  // At the top of the file: no table in the message, and a table is called one.
  const Table root = root_of("name = \"x\"\n[rn]\n");
  EXPECT_EQ(error_of([&] {
              root.refuse_unknown({"name", "run"});
            }),
            "t.toml: rn: unknown table (known: name, run)");
  // An absent table has no keys to refuse, and reads leave their defaults.
  const Table absent = root.table("run");
  EXPECT_FALSE(absent.present());
  EXPECT_EQ(error_of([&] { absent.refuse_unknown({}); }), "");
  double v = 7.0;
  EXPECT_FALSE(absent.number("rate_hz", v, {0.0, 1.0}));
  EXPECT_EQ(v, 7.0);
}

TEST(TomlReader, RangesHaveOpenAndClosedEnds) {
  const Table t =
      root_of("[a]\nzero = 0\none = 1.0\nhalf = 0.5\nbig = 1e300\nnan = nan\n").table("a");
  double v = -1.0;
  EXPECT_TRUE(t.number("zero", v, {0.0, 1.0}));  // closed ends hold their end
  EXPECT_EQ(v, 0.0);
  EXPECT_TRUE(t.number("one", v, {0.0, 1.0}));
  EXPECT_EQ(v, 1.0);
  EXPECT_EQ(error_of([&] {
              t.number("zero", v, {0.0, 1.0, true});
            }),
            "t.toml: [a] zero: 0 is outside (0, 1]");
  EXPECT_EQ(error_of([&] {
              t.number("one", v, {0.0, 1.0, false, true});
            }),
            "t.toml: [a] one: 1 is outside [0, 1)");
  EXPECT_EQ(error_of([&] { t.number("half", v, {0.0, 1.0, true, true}); }), "");
  EXPECT_EQ(v, 0.5);
  EXPECT_EQ(error_of([&] {
              t.number("big", v, {0.0, 1e6});
            }),
            "t.toml: [a] big: 1e+300 is outside [0, 1e+06]");
  // Not finite is never inside, whatever the range.
  EXPECT_EQ(error_of([&] {
              t.number("nan", v, {-1e308, 1e308});
            }),
            "t.toml: [a] nan: nan is outside [-1e+308, 1e+308]");
  // An integer is a number; a number is not an integer.
  int n = 0;
  EXPECT_TRUE(t.integer("zero", n, 0, 3));
  EXPECT_EQ(error_of([&] { t.integer("one", n, 0, 3); }),
            "t.toml: [a] one: expected an integer, got a floating-point number");
  EXPECT_EQ(error_of([&] { t.integer("zero", n, 1, 3); }), "t.toml: [a] zero: 0 is outside [1, 3]");
}

TEST(TomlReader, DegreesAndDecibelsAreConvertedOnReading) {
  const Table t =
      root_of("[antenna]\nazimuth_deg = 90\ntilt_deg = -400\ngain_db = 30\n").table("antenna");
  double az_rad = 0.0;
  EXPECT_TRUE(t.degrees("azimuth_deg", az_rad, {-180.0, 180.0}));
  EXPECT_EQ(az_rad, 90.0 * (std::numbers::pi / 180.0));
  // The range is in the file's unit (degrees), and so is the message.
  EXPECT_EQ(error_of([&] {
              t.degrees("tilt_deg", az_rad, {-360.0, 360.0});
            }),
            "t.toml: [antenna] tilt_deg: -400 is outside [-360, 360]");
  double gain = 0.0;
  EXPECT_TRUE(t.decibels("gain_db", gain, {0.0, 80.0}));
  EXPECT_DOUBLE_EQ(gain, 1000.0);
  double absent_rad = 0.25;
  EXPECT_FALSE(t.degrees("elevation_deg", absent_rad, {-90.0, 90.0}));
  EXPECT_EQ(absent_rad, 0.25);  // the default stays, unconverted
}

TEST(TomlReader, WrongTypesAreNamed) {
  const Table t =
      root_of("[x]\ns = \"text\"\ni = 3\nb = true\na = [1, 2]\nd = 2024-01-01\n[x.sub]\n")
          .table("x");
  double v = 0.0;
  bool flag = false;
  std::string text;
  EXPECT_EQ(error_of([&] {
              t.number("s", v, {0, 1});
            }),
            "t.toml: [x] s: expected a number, got a string");
  EXPECT_EQ(error_of([&] { t.boolean("i", flag); }),
            "t.toml: [x] i: expected true or false, got an integer");
  EXPECT_EQ(error_of([&] { t.string("b", text); }),
            "t.toml: [x] b: expected a string, got a boolean");
  EXPECT_EQ(error_of([&] {
              t.number("a", v, {0, 1});
            }),
            "t.toml: [x] a: expected a number, got an array");
  EXPECT_EQ(error_of([&] { t.string("d", text); }), "t.toml: [x] d: expected a string, got a date");
  EXPECT_EQ(error_of([&] { (void)t.table("s"); }), "t.toml: [x] s: expected a table, got a string");
  // A sub-table is named by its dotted path.
  EXPECT_EQ(error_of([&] { t.table("sub").fail("k", "what"); }), "t.toml: [x.sub] k: what");
}

TEST(TomlReader, ChoicesListTheKnownValues) {
  const Table t = root_of("mode = \"fast\"\nlook = \"left\"\n");
  std::string mode = "auto", look = "right";
  EXPECT_EQ(error_of([&] {
              t.choice("mode", mode, {"auto", "model"});
            }),
            "t.toml: mode: unknown value \"fast\" (known: auto, model)");
  EXPECT_EQ(mode, "auto");
  EXPECT_TRUE(t.choice("look", look, {"right", "left"}));
  EXPECT_EQ(look, "left");
}

TEST(TomlReader, VectorsHaveAFixedLengthAndRangedElements) {
  const Table t =
      root_of(
          "[o]\np = [1, 2.5, -3]\nshort = [1, 2]\nfar = [0, 2e6, 0]\nword = [0, \"a\", 0]\n"
          "path = [[0, 0, 0], [1, 1, 1]]\nbadpath = [[0, 0, 0], [1, 1]]\n")
          .table("o");
  std::array<double, 3> p{};
  EXPECT_TRUE(t.vector("p", p, {-10.0, 10.0}));
  EXPECT_EQ(p, (std::array<double, 3>{1.0, 2.5, -3.0}));
  EXPECT_EQ(error_of([&] {
              t.vector("short", p, {-10.0, 10.0});
            }),
            "t.toml: [o] short: expected an array of 3 numbers, got an array of 2");
  EXPECT_EQ(error_of([&] {
              t.vector("far", p, {-1e6, 1e6});
            }),
            "t.toml: [o] far[1]: 2e+06 is outside [-1e+06, 1e+06]");
  EXPECT_EQ(error_of([&] {
              t.vector("word", p, {-1e6, 1e6});
            }),
            "t.toml: [o] word[1]: expected a number, got a string");
  EXPECT_EQ(p, (std::array<double, 3>{1.0, 2.5, -3.0}));  // untouched by the failed reads
  const auto path = t.vectors("path", 3, {-10.0, 10.0});
  ASSERT_TRUE(path.has_value());
  ASSERT_EQ(path->size(), 2u);
  EXPECT_EQ((*path)[1], (std::vector<double>{1.0, 1.0, 1.0}));
  EXPECT_EQ(error_of([&] {
              (void)t.vectors("badpath", 3, {-10.0, 10.0});
            }),
            "t.toml: [o] badpath[1]: expected an array of 3 numbers, got an array of 2");
  EXPECT_FALSE(t.vectors("none", 3, {0.0, 1.0}).has_value());
}

TEST(TomlReader, ArraysOfTablesAreNumberedFromOne) {
  const Table root = root_of(
      "[[target]]\nname = \"a\"\n[[target]]\nspeed = 3\n[scene]\n[[scene.target]]\nkind = 1\n");
  const std::vector<Table> targets = root.tables("target");
  ASSERT_EQ(targets.size(), 2u);
  EXPECT_EQ(targets[0].name(), "[[target]] #1");
  EXPECT_EQ(error_of([&] { targets[1].refuse_unknown({"name"}); }),
            "t.toml: [[target]] #2 speed: unknown key (known: name)");
  const std::vector<Table> nested = root.table("scene").tables("target");
  ASSERT_EQ(nested.size(), 1u);
  std::string kind;
  EXPECT_EQ(error_of([&] { nested[0].string("kind", kind); }),
            "t.toml: [[scene.target]] #1 kind: expected a string, got an integer");
  // Absent or empty: none. A single table or a plain value is not an array of tables.
  EXPECT_TRUE(root.tables("none").empty());
  EXPECT_TRUE(root_of("target = []\n").tables("target").empty());
  EXPECT_EQ(error_of([&] { (void)root_of("[target]\n").tables("target"); }),
            "t.toml: target: expected [[target]] tables (an array of tables), got a table");
  EXPECT_EQ(error_of([&] { (void)root_of("target = [1]\n").tables("target"); }),
            "t.toml: target: expected [[target]] tables (an array of tables), got an array "
            "holding an integer");
}

TEST(TomlReader, RequiredKeysAndWholeTableMessages) {
  const Table t = root_of("[w]\nx = 1\n").table("w");
  EXPECT_EQ(error_of([&] { t.require("x"); }), "");
  EXPECT_EQ(error_of([&] { t.require("speed_mps", "with waypoints_enu_m"); }),
            "t.toml: [w] speed_mps: is required with waypoints_enu_m");
  EXPECT_EQ(error_of([&] { t.fail("", "needs x or y"); }), "t.toml: [w] needs x or y");
  EXPECT_EQ(config::error_text("f.toml", "", "key", "what"), "f.toml: key: what");
  EXPECT_EQ(config::error_text("f.toml", "", "", "what"), "f.toml: what");
}

TEST(TomlReader, SyntaxErrorsCarryLineAndColumn) {
  EXPECT_EQ(error_of([] {
              (void)TomlFile::parse("[run]\nframes = = 3\n", "s.toml");
            }).rfind("s.toml:2:10: ", 0),
            0u);
  const std::string e = error_of([] { (void)TomlFile::parse("[run\n", "s.toml"); });
  EXPECT_EQ(e.rfind("s.toml:1:5: ", 0), 0u) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  EXPECT_EQ(error_of([] { (void)TomlFile::load("/nonexistent/dir/c.toml"); }),
            "/nonexistent/dir/c.toml: cannot open for reading");
}

TEST(TomlReader, NumbersTakeOneOrMany) {
  const Table t = root_of("one = 2\nmany = [1, 2.5]\nbad = [1, \"x\"]\n");
  EXPECT_EQ(*t.numbers("one"), (std::vector<double>{2.0}));
  EXPECT_EQ(*t.numbers("many"), (std::vector<double>{1.0, 2.5}));
  EXPECT_EQ(error_of([&] { (void)t.numbers("bad"); }),
            "t.toml: bad: expected a number or an array of numbers, got an array holding a string");
  EXPECT_FALSE(t.numbers("none").has_value());
}

// Replays every checked-in input of every harness (tests/fuzz/corpus/<name>/: the seeds;
// tests/fuzz/regressions/<name>/: inputs that once crashed a harness, kept as regression tests)
// through the harness, in the normal build and under ASan+UBSan (label "sanitize"). A
// regression that comes back aborts the test (FUZZ_CHECK) or trips a sanitizer.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>
#include <string>
#include <vector>

#include "tests/fuzz/harnesses.hpp"

namespace radar_emu::fuzz {
namespace {

using Harness = int (*)(const std::uint8_t*, std::size_t);

struct Target {
  const char* name;
  Harness run;
};

constexpr Target kTargets[] = {
    {"canaerospace", canaerospace},
    {"icd_classic", icd_classic},
    {"icd_fd", icd_fd},
    {"candump", candump},
    {"modbus_nav", modbus_nav},
    {"modbus_table", modbus_table},
    {"scenario_toml", scenario_toml},
    {"gltf", gltf},
    {"obj", obj},
    {"stl", stl},
    {"websocket", websocket},
    {"sar_case", sar_case},
};

// gtest prints the parameter in test listings: its name, not its bytes.
void PrintTo(const Target& t, std::ostream* os) {
  *os << t.name;
}

std::vector<std::filesystem::path> inputs(const std::string& kind, const std::string& name) {
  std::vector<std::filesystem::path> files;
  const std::filesystem::path dir = std::filesystem::path(RADAR_EMU_FUZZ_DIR) / kind / name;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    if (e.is_regular_file() && e.path().filename() != "README.md")
      files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<std::uint8_t> read_all(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class Replay : public ::testing::TestWithParam<Target> {};

TEST_P(Replay, SeedCorpusRunsClean) {
  const Target t = GetParam();
  const auto files = inputs("corpus", t.name);
  ASSERT_FALSE(files.empty()) << "no seeds in tests/fuzz/corpus/" << t.name;
  for (const auto& f : files) {
    SCOPED_TRACE(f.string());
    const std::vector<std::uint8_t> data = read_all(f);
    EXPECT_EQ(t.run(data.data(), data.size()), 0);
  }
  // The empty input too (libFuzzer always tries it).
  EXPECT_EQ(t.run(nullptr, 0), 0);
}

TEST_P(Replay, RegressionInputsRunClean) {
  const Target t = GetParam();
  for (const auto& f : inputs("regressions", t.name)) {
    SCOPED_TRACE(f.string());
    const std::vector<std::uint8_t> data = read_all(f);
    EXPECT_EQ(t.run(data.data(), data.size()), 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Fuzz, Replay, ::testing::ValuesIn(kTargets),
                         [](const auto& p) { return std::string(p.param.name); });

}  // namespace
}  // namespace radar_emu::fuzz

// Option parsing of the offline RCS tools (a parser: runs under ASan + UBSan too).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "config/cli_args.hpp"
#include "tools/rcs.hpp"

namespace config = radar_emu::config;
using radar_emu::common::Polarisation;
namespace tools = radar_emu::tools;

namespace {

TEST(RcsTool, ParseSweep) {
  EXPECT_EQ(config::parse_sweep("10e9", "--freq-hz"), (std::vector<double>{10e9}));
  EXPECT_EQ(config::parse_sweep("0:90:3", "--theta-deg"), (std::vector<double>{0.0, 45.0, 90.0}));
  EXPECT_EQ(config::parse_sweep("5:1:1", "--phi-deg"), (std::vector<double>{5.0}));
  const auto down = config::parse_sweep("90:-90:5", "--phi-deg");
  EXPECT_EQ(down.front(), 90.0);
  EXPECT_EQ(down.back(), -90.0);
  for (const char* bad : {"", "abc", "1:2", "1:2:0", "1:2:1.5", "1:1:3", "nan", "1:2:3:4", "1e400",
                          "1:2:2000000", "0:1:-1"}) {
    EXPECT_THROW((void)config::parse_sweep(bad, "--x"), std::invalid_argument) << bad;
  }
  try {
    (void)config::parse_sweep("1:x:3", "--theta-deg");
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--theta-deg: 'x'"), std::string::npos) << e.what();
  }
}

TEST(RcsTool, ParsePols) {
  EXPECT_EQ(tools::parse_pols("hh,VV,hv"),
            (std::vector<Polarisation>{Polarisation::kHH, Polarisation::kVV, Polarisation::kHV}));
  EXPECT_EQ(tools::parse_pols("VV,VV"), (std::vector<Polarisation>{Polarisation::kVV}));
  EXPECT_THROW((void)tools::parse_pols("HH,"), std::invalid_argument);
  EXPECT_THROW((void)tools::parse_pols("XX"), std::invalid_argument);
  try {
    (void)tools::parse_pols("HH,xv");
    ADD_FAILURE() << "xv accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "--pol: 'xv' is not one of HH, HV, VH, VV");
  }
}

TEST(RcsTool, MaterialDefinitions) {
  const std::filesystem::path p = std::filesystem::path(::testing::TempDir()) / "glass.obj";
  std::ofstream(p) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl glass\nf 1 2 3\nusemtl metal\n"
                   << "v 0 0 1\nf 1 2 4\n";
  const tools::LoadedTarget t = tools::load_target(p.string(), 1.0, {"glass=6.5,0.3"});
  ASSERT_EQ(t.surfaces.size(), 2u);
  EXPECT_EQ(t.surfaces[0].kind, radar_emu::radar::SurfaceModel::Kind::kDielectric);
  EXPECT_EQ(t.surfaces[0].relative_permittivity, std::complex<double>(6.5, -0.3));
  EXPECT_EQ(t.surfaces[1].kind, radar_emu::radar::SurfaceModel::Kind::kPec);
  const tools::LoadedTarget c =
      tools::load_target(p.string(), 1.0, {"glass=3,0.1,0.002", "paint=2,0"});
  EXPECT_EQ(c.surfaces[0].kind, radar_emu::radar::SurfaceModel::Kind::kCoatedPec);
  EXPECT_DOUBLE_EQ(c.surfaces[0].thickness_m, 0.002);
  bool warned = false;
  for (const std::string& w : c.warnings)
    warned |= w.find("--material paint") != std::string::npos;
  EXPECT_TRUE(warned);
  for (const char* bad :
       {"glass", "=1,0", "glass=0.5,0", "glass=4,-1", "glass=4,0,0", "glass=4", "glass=a,b"}) {
    EXPECT_THROW((void)tools::load_target(p.string(), 1.0, {bad}), std::invalid_argument) << bad;
  }
  EXPECT_THROW((void)tools::load_target(p.string(), 1.0, {}), std::invalid_argument);  // glass?
  EXPECT_THROW((void)tools::load_target(p.string(), -1.0, {"glass=2,0"}), std::invalid_argument);
}

}  // namespace

#pragma once
// The libFuzzer harnesses (tests/fuzz/README.md). Each takes one input and returns 0; a crash,
// a sanitizer report or a broken invariant (FUZZ_CHECK) is a finding. The same functions are
// the body of each fuzzer (fuzz_main.cpp) and of the replay test over the checked-in corpora
// and regression inputs (replay_test.cpp), so the normal gcc build runs every seed too.

#include <cstddef>
#include <cstdint>

namespace radar_emu::fuzz {

int canaerospace(const std::uint8_t* data, std::size_t size);   // io/canaerospace
int icd_classic(const std::uint8_t* data, std::size_t size);    // io/detection_icd, classic CAN
int icd_fd(const std::uint8_t* data, std::size_t size);         // io/detection_icd, CAN FD
int candump(const std::uint8_t* data, std::size_t size);        // io/candump
int modbus_nav(const std::uint8_t* data, std::size_t size);     // io/modbus_map, navigation map
int modbus_table(const std::uint8_t* data, std::size_t size);   // io/modbus_map, detection table
int scenario_toml(const std::uint8_t* data, std::size_t size);  // loop/scenario
int gltf(const std::uint8_t* data, std::size_t size);           // scene/gltf (.gltf and .glb)
int obj(const std::uint8_t* data, std::size_t size);            // scene/mesh_io, Wavefront OBJ
int stl(const std::uint8_t* data, std::size_t size);            // scene/mesh_io, STL
int websocket(const std::uint8_t* data, std::size_t size);      // io/websocket, requests, frames
int sar_case(const std::uint8_t* data, std::size_t size);       // tools/sar, TOML case

}  // namespace radar_emu::fuzz

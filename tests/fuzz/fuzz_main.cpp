// The libFuzzer entry point of one harness: compiled once per fuzzer with
// RADAR_EMU_FUZZ_TARGET set to the harness function (tests/fuzz/CMakeLists.txt).

#include <cstddef>
#include <cstdint>

#include "tests/fuzz/harnesses.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return radar_emu::fuzz::RADAR_EMU_FUZZ_TARGET(data, size);
}

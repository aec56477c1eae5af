# Warning flags and sanitizers as INTERFACE targets that every project target links.
add_library(radar_emu_warnings INTERFACE)
target_compile_options(radar_emu_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast -Wcast-align
  -Woverloaded-virtual -Wconversion -Wsign-conversion -Wdouble-promotion
  -Wimplicit-fallthrough -Wformat=2)
if(RADAR_EMU_WERROR)
  target_compile_options(radar_emu_warnings INTERFACE -Werror)
  # GCC 12 at -O3 (Release) reports -Wrestrict inside std::string's own operator+ / replace
  # (GCC bug 105651) and -Warray-bounds inside std::copy into a std::vector (bug 107852), false
  # positives in libstdc++: warnings still, not errors.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    target_compile_options(radar_emu_warnings INTERFACE -Wno-error=restrict
                                                        -Wno-error=array-bounds)
  endif()
endif()

add_library(radar_emu_sanitizers INTERFACE)
if(RADAR_EMU_FUZZ)
  # libFuzzer (tests/fuzz, scripts/fuzz.sh): every project library gets coverage instrumentation
  # and ASan+UBSan; the harness executables add -fsanitize=fuzzer (libFuzzer's main).
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "RADAR_EMU_FUZZ needs clang (Debian 12: clang-14); configure a separate "
                        "build tree with -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++")
  endif()
  # Line tables (stack traces with lines); configure with CMAKE_BUILD_TYPE=Debug so that
  # assertions stay on. The libraries and the harnesses are compiled at RADAR_EMU_FUZZ_OPT:
  # -O1 by default (what OSS-Fuzz builds with: fast enough to fuzz; scripts/fuzz.sh), -O0 in
  # the CI's sanitizer tree (scripts/test.sh), which compiles them in about 0.6 of the time
  # (tools/sar.cpp 20.4 against 10.1 s of CPU, clang 14) and fuzzes each harness for seconds
  # only, where compile time is most of the stage. The test suites built in the same tree keep
  # Debug's -O0 (their time is in the libraries, and -O1 doubled their compile).
  set(RADAR_EMU_FUZZ_OPT "-O1" CACHE STRING
      "Optimisation of the libraries and harnesses in a RADAR_EMU_FUZZ tree (-O1 or -O0)")
  set_property(CACHE RADAR_EMU_FUZZ_OPT PROPERTY STRINGS -O0 -O1 -O2)
  target_compile_options(radar_emu_sanitizers INTERFACE
    -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
    -gline-tables-only)
  target_link_options(radar_emu_sanitizers INTERFACE -fsanitize=address,undefined)
elseif(RADAR_EMU_SANITIZE)
  target_compile_options(radar_emu_sanitizers INTERFACE
    -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  target_link_options(radar_emu_sanitizers INTERFACE -fsanitize=address,undefined)
endif()

# radar_emu_module(NAME <name> SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Declares the library radar_emu_<name> (alias radar_emu::<name>) with the project root as
# include directory, so headers read "#include \"<folder>/<file>.hpp\"". Every module links
# radar_emu::common (common/, header-only) PUBLIC.
function(radar_emu_module)
  cmake_parse_arguments(M "" "NAME" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(radar_emu_${M_NAME} STATIC ${M_SOURCES})
  add_library(radar_emu::${M_NAME} ALIAS radar_emu_${M_NAME})
  target_include_directories(radar_emu_${M_NAME} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(radar_emu_${M_NAME}
    PUBLIC radar_emu::common ${M_PUBLIC_DEPS} radar_emu_sanitizers
    PRIVATE ${M_PRIVATE_DEPS} radar_emu_warnings)
  set_target_properties(radar_emu_${M_NAME} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  if(RADAR_EMU_FUZZ)
    target_compile_options(radar_emu_${M_NAME} PRIVATE ${RADAR_EMU_FUZZ_OPT})
  endif()
endfunction()

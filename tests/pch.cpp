// The translation unit that carries the suites' precompiled GoogleTest header
// (tests/CMakeLists.txt, radar_emu_test_pch).

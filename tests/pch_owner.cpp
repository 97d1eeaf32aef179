// Nothing: the object library this file belongs to (tests/CMakeLists.txt,
// cellbake_test_pch) only builds the test programs' precompiled header.

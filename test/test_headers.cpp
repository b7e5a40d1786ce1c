// The translation unit that precompiles the tests' common headers (test/CMakeLists.txt).

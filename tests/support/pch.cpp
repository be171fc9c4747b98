// An empty source: afhub_test_pch exists to build the tests' precompiled header.

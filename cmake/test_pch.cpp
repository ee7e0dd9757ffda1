// The target that compiles the tests' precompiled header (<gtest/gtest.h>); it has no code of its own.

// Hostile input and hard cases (issue 39): output.

#include <gtest/gtest.h>

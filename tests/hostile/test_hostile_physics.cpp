// Hostile input and hard cases (issue 39): physics.

#include <gtest/gtest.h>

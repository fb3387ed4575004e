// Hostile input and hard cases (issue 39): input.

#include <gtest/gtest.h>

// Placeholder while exploring
#include <gtest/gtest.h>

#include <gtest/gtest.h>

#include "core/rng.h"

TEST(Pcg32, SameKeySameStream) {
  caustica::Pcg32 a = caustica::Pcg32::for_sample(5, 3, 1), b = caustica::Pcg32::for_sample(5, 3, 1);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(a.next_u32(), b.next_u32());
}

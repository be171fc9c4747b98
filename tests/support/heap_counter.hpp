// Counts every C++ heap allocation of the test binary it is linked into (its
// operator new replaces the standard one), for tests that a cycle allocates nothing:
//   const long before = heap_allocations();  ...  EXPECT_EQ(heap_allocations(), before);
#pragma once

namespace afhub::test {

long heap_allocations() noexcept;

}  // namespace afhub::test

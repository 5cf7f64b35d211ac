#pragma once
// Counts heap allocations made through the global operator new, so a test can prove a code path
// allocates nothing. Linking graspbed_allocation_counter replaces the global allocation functions of
// that test executable (and only of the executables that link it).

namespace graspbed::test_support {

/// Global operator new / new[] calls since the program started.
long AllocationCount();

}  // namespace graspbed::test_support

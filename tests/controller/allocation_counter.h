#pragma once
/// Counts heap allocations made through the global operator new in the test binary that links
/// allocation_counter.cc, so tests can prove a code path allocates nothing.

namespace graspbed::controller::testing {

/// Global operator new calls since the program started.
long AllocationCount();

}  // namespace graspbed::controller::testing

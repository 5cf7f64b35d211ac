#pragma once
/// Counts heap allocations made through the global operator new in the sim test binary, so tests
/// can prove the per-step path allocates nothing.

namespace graspbed::sim::testing {

/// Global operator new calls since the program started.
long AllocationCount();

}  // namespace graspbed::sim::testing

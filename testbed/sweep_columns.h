#pragma once
/// The columns of a sweep's results.csv and results.jsonl rows that are the sweep's own (not a swept
/// parameter), declared once for the sweep that writes them (testbed/sweep.cc) and the report that
/// reads them back (testbed/report.cc, which links nothing of the simulation). docs/scenarios.md,
/// "Sweeps".

#include <array>

namespace graspbed::testbed {

/// The run's metrics, in CSV order after the parameter columns.
inline constexpr std::array<const char*, 14> kSweepMetricColumns = {"passed",
                                                                    "completed",
                                                                    "dropped",
                                                                    "max_slip_mm",
                                                                    "peak_grip_n",
                                                                    "crushed",
                                                                    "slip_detect_latency_ms",
                                                                    "false_slip_per_min",
                                                                    "fn_rmse_n",
                                                                    "ft_rmse_n",
                                                                    "time_to_stable_s",
                                                                    "sim_s",
                                                                    "wall_s",
                                                                    "failed_expectations"};
/// The row's identity, before the parameter columns.
inline constexpr std::array<const char*, 2> kSweepRowColumns = {"run", "scenario"};
/// Present on a row whose run threw instead of finishing (JSON lines only).
inline constexpr const char* kSweepErrorKey = "error";

}  // namespace graspbed::testbed

#include "sensor/tactile_state.h"

namespace graspbed::sensor {

const char* ToString(UnitValidity validity) {
  switch (validity) {
    case UnitValidity::kValid: return "valid";
    case UnitValidity::kOpen: return "open";
    case UnitValidity::kShort: return "short";
    case UnitValidity::kOutOfRange: return "out_of_range";
    case UnitValidity::kImplausible: return "implausible";
    case UnitValidity::kNotTared: return "not_tared";
  }
  return "unknown";
}

}  // namespace graspbed::sensor

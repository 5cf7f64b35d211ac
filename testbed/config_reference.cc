#include "testbed/config_reference.h"

#include "hardware/hardware_config.h"
#include "sensor/fea/fea_config.h"
#include "sensor/inversion.h"
#include "sensor/readout.h"
#include "sensor/strain_model.h"
#include "sim/proprioception.h"
#include "sim/scene_config.h"
#include "testbed/scenario_config.h"

namespace graspbed::testbed {

std::vector<ConfigSection> ConfigReference() {
  return {
      {"object", sim::ObjectConfigFields().Reference()},
      {"hand", sim::HandConfigFields().Reference()},
      {"physics", sim::PhysicsConfigFields().Reference()},
      {"sensor", SensorOptionsFields().Reference()},
      {"sensor.strain_model", sensor::StrainModelConfigFields().Reference()},
      {"sensor.readout", sensor::ReadoutConfigFields().Reference()},
      {"sensor.inversion", sensor::InversionConfigFields().Reference()},
      {"proprioception", sim::ProprioceptionConfigFields().Reference()},
      {"controller", ControllerOptionsFields().Reference()},
      {"expectations", ExpectationsFields().Reference()},
      {"metrics", MetricsConfigFields().Reference()},
      {"serial", hardware::HardwareConfigFields().Reference()},
      {"fea", fea::FeaConfigFields().Reference()},
  };
}

std::string ConfigReferenceMarkdown(const std::string& path) {
  std::string known;
  for (const ConfigSection& section : ConfigReference()) {
    if (section.path == path) return common::ReferenceMarkdown(section.rows);
    known += (known.empty() ? "" : ", ") + section.path;
  }
  throw common::ConfigError("", 0, "section", path, "no such config section; sections: " + known);
}

}  // namespace graspbed::testbed

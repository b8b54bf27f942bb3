#pragma once
// EstimatorConfig <-> YAML (the `slam:` section of run configs). Unknown keys are errors naming file:line.
#include <string>

#include "core/pipeline/estimator_config.hpp"
#include "core/util/status.hpp"

namespace YAML {
class Node;
class Emitter;
}  // namespace YAML

namespace rotolidar {

/// Parses `node` (a mapping) into *config, starting from its current values; validates the result.
Status ParseEstimatorConfig(const std::string& file, const YAML::Node& node, EstimatorConfig* config);
/// Emits every field (the resolved config) as a YAML mapping.
void EmitEstimatorConfig(YAML::Emitter& out, const EstimatorConfig& config);

}  // namespace rotolidar

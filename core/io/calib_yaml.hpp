#pragma once
// calib.yaml <-> RigCalib (docs/recording_format.md). Unknown keys are errors; every error names file:line and
// the field. The loaded calibration is validated (RigCalib::Validate) before it is returned.
#include <string>

#include "core/types/calib.hpp"
#include "core/util/status.hpp"

namespace rotolidar {

Status LoadCalibYaml(const std::string& path, RigCalib* calib);
Status SaveCalibYaml(const std::string& path, const RigCalib& calib);

}  // namespace rotolidar

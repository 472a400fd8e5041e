// The real rig a run config names (rig.type: hardware): the command line is
// the only part of the testbed that builds it.
#pragma once

#include <memory>

#include "experiments/config/config.h"
#include "rig/hardware/hardware_rig.h"
#include "rig/hardware/indexer_emulator.h"

namespace experiments {

/// The HardwareRig of `config`: stages on rig.port (or on the indexer
/// emulator, started into `*emulator` with rig.emulate_stages), cameras and
/// calibration from the config; unit addresses and directions from rig.units
/// and rig.directions, limits and steps from the rig.* keys. Throws
/// rig::InputError for a calibration that does not fit the config,
/// rig::RigError for a device that fails.
std::unique_ptr<rig::HardwareRig> MakeHardwareRig(const RunConfig& config,
                                                  std::unique_ptr<rig::IndexerEmulator>* emulator);

}  // namespace experiments

// Reads AMBF's input device file (input_devices.yaml): an "input devices" list of
// block names, one block per device. Problems are thrown as afhub::Error
// "file:line:col: error: ..." and unknown keys give "file:line:col: warning: ...",
// as the ADF loader does.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "afhub/teleop/input_device_spec.hpp"

namespace afhub::teleop {

struct InputDevicesFile {
  std::string path;
  std::vector<InputDeviceSpec> devices;  // in the order of the "input devices" list
  std::vector<std::string> warnings;     // "file:line:col: warning: ..."
};

InputDevicesFile read_input_devices(const std::string& path);

// The devices `-d 0,1` selects, by index into the "input devices" list, in the order
// given; an empty selection selects them all. The selected devices' simulated
// multibody files must exist. Errors name the selection and the devices there are.
std::vector<InputDeviceSpec> select_devices(const InputDevicesFile& file,
                                            const std::string& selection);

}  // namespace afhub::teleop

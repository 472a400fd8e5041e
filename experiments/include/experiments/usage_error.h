// The error of anything the user typed or wrote (flags, configs, sweep
// files): the command line prints its message and exits with 2.
#pragma once

#include "rig/input_file.h"

namespace experiments {

/// Thrown for bad command-line or configuration input; the message names the
/// flag or key and the problem.
class UsageError : public rig::InputError {
 public:
  using rig::InputError::InputError;
};

}  // namespace experiments

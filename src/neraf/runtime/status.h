#pragma once
// Error reporting of the C API: a status code plus a one-line message kept per thread (as errno),
// and the pose checks every query and stream shares. Internal to neraf_rt.
#include <string>

#include "neraf/neraf_rt.h"

namespace neraf::rt {

// Stores `message` as this thread's neraf_last_error() and returns `status` (for
// `return fail(NERAF_ERR_IO, path + ": cannot open");`).
neraf_status fail(neraf_status status, const std::string& message);

// NERAF_ERR_NOT_FINITE for a NaN/infinite coordinate or yaw, NERAF_ERR_OUTSIDE for a mic or
// source outside [box_min, box_max] unless flags has NERAF_ALLOW_OUTSIDE, NERAF_ERR_INVALID_ARGUMENT
// for an unknown flag; the message names the coordinate and the box.
neraf_status validate_pose(const neraf_model_info& info, const neraf_pose& pose, unsigned flags);

}  // namespace neraf::rt

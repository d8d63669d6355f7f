#include "neraf/runtime/status.h"

#include <cmath>
#include <cstdio>

namespace neraf::rt {

namespace {
// The message of this thread's last failing call (what neraf_last_error returns).
thread_local std::string last_error_message;

// The open box, as the engine's input encoding: a position on a face (or outside) is encoded as
// zeros (normalize_position), so its prediction would not describe it.
bool inside(const double p[3], const neraf_model_info& info) {
  for (int i = 0; i < 3; ++i)
    if (!(p[i] > info.box_min[i] && p[i] < info.box_max[i])) return false;
  return true;
}

std::string describe(const char* what, const double p[3], const neraf_model_info& info) {
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "%s (%.3f, %.3f, %.3f) is outside the training box [%.3f, %.3f] x [%.3f, %.3f] x "
                "[%.3f, %.3f] m (open: its faces count as outside); move it inside or allow poses "
                "outside the box",
                what, p[0], p[1], p[2], info.box_min[0], info.box_max[0], info.box_min[1],
                info.box_max[1], info.box_min[2], info.box_max[2]);
  return buf;
}
}  // namespace

neraf_status fail(neraf_status status, const std::string& message) {
  try {
    last_error_message = message;
  } catch (...) {  // out of memory while reporting: keep the status
  }
  return status;
}

neraf_status validate_pose(const neraf_model_info& info, const neraf_pose& pose, unsigned flags) {
  if (flags & ~NERAF_ALLOW_OUTSIDE) return fail(NERAF_ERR_INVALID_ARGUMENT, "unknown query flag");
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(pose.mic[i]) || !std::isfinite(pose.source[i]))
      return fail(NERAF_ERR_NOT_FINITE,
                  "pose: a microphone or source coordinate is NaN or infinite");
  if (!std::isfinite(pose.yaw_deg))
    return fail(NERAF_ERR_NOT_FINITE, "pose: yaw is NaN or infinite");
  if (!(flags & NERAF_ALLOW_OUTSIDE)) {
    if (!inside(pose.mic, info))
      return fail(NERAF_ERR_OUTSIDE, describe("microphone", pose.mic, info));
    if (!inside(pose.source, info))
      return fail(NERAF_ERR_OUTSIDE, describe("source", pose.source, info));
  }
  return NERAF_OK;
}

}  // namespace neraf::rt

extern "C" NERAF_RT_API const char* neraf_last_error(void) {
  return neraf::rt::last_error_message.c_str();
}

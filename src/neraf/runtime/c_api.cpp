// The model, workspace and query functions of neraf_rt.h (the stream functions are in
// stream.cpp, neraf_last_error in status.cpp). Every entry point checks its arguments, catches
// every exception and reports it as a status plus neraf_last_error().
#include <new>
#include <string>
#include <system_error>

#include "neraf/neraf_rt.h"
#include "neraf/runtime/c_api_types.h"
#include "neraf/runtime/model_file.h"
#include "neraf/runtime/status.h"

using neraf::rt::fail;

namespace {

// Runs fn() (returning a neraf_status), turning exceptions into statuses; `what` prefixes the
// messages of unexpected ones.
template <typename Fn>
neraf_status guarded(const char* what, Fn&& fn) noexcept {
  try {
    return fn();
  } catch (const neraf::rt::ModelFileError& e) {
    return fail(e.status(), e.what());
  } catch (const std::bad_alloc&) {
    return fail(NERAF_ERR_OUT_OF_MEMORY, std::string(what) + ": out of memory");
  } catch (const std::system_error& e) {
    return fail(NERAF_ERR_INTERNAL, std::string(what) + ": " + e.what());
  } catch (const std::exception& e) {
    return fail(NERAF_ERR_INTERNAL, std::string(what) + ": " + e.what());
  } catch (...) {
    return fail(NERAF_ERR_INTERNAL, std::string(what) + ": unknown error");
  }
}

// The checks both queries share; on success the pose is valid for the model.
neraf_status check_query(const char* what, const neraf_model* model, neraf_workspace* workspace,
                         const neraf_pose* pose, unsigned flags, const float* out, size_t capacity,
                         size_t needed) {
  if (!model || !workspace || !pose || !out)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                std::string(what) + ": model, workspace, pose and out must not be NULL");
  if (workspace->model != model)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                std::string(what) + ": the workspace was created for another model");
  if (capacity < needed)
    return fail(NERAF_ERR_BUFFER_TOO_SMALL,
                std::string(what) + ": out holds " + std::to_string(capacity) +
                    " floats, the query writes " + std::to_string(needed));
  return neraf::rt::validate_pose(model->info, *pose, flags);
}

}  // namespace

extern "C" {

NERAF_RT_API const char* neraf_status_string(neraf_status status) {
  switch (status) {
    case NERAF_OK:
      return "ok";
    case NERAF_ERR_INVALID_ARGUMENT:
      return "invalid argument";
    case NERAF_ERR_IO:
      return "input/output error";
    case NERAF_ERR_FORMAT:
      return "not a valid neraf model file";
    case NERAF_ERR_VERSION:
      return "model written by a newer neraf";
    case NERAF_ERR_NOT_FINITE:
      return "NaN or infinite value";
    case NERAF_ERR_OUTSIDE:
      return "pose outside the training box";
    case NERAF_ERR_BUFFER_TOO_SMALL:
      return "output buffer too small";
    case NERAF_ERR_OUT_OF_MEMORY:
      return "out of memory";
    case NERAF_ERR_INTERNAL:
      return "internal error";
  }
  return "unknown status";
}

NERAF_RT_API neraf_status neraf_model_load_ex(const char* path, unsigned flags, neraf_model** out) {
  if (out) *out = nullptr;
  if (!path || !out)
    return fail(NERAF_ERR_INVALID_ARGUMENT, "neraf_model_load: path and out must not be NULL");
  if (flags & ~NERAF_LOAD_FLOAT32)
    return fail(NERAF_ERR_INVALID_ARGUMENT, "neraf_model_load_ex: unknown flag");
  return guarded("neraf_model_load", [&] {
    const std::string name(path);
    const neraf::rt::ModelData data = neraf::rt::read_model_file(name);
    *out = new neraf_model(data, name, !(flags & NERAF_LOAD_FLOAT32));
    return NERAF_OK;
  });
}

NERAF_RT_API neraf_status neraf_model_load(const char* path, neraf_model** out) {
  return neraf_model_load_ex(path, 0, out);
}

NERAF_RT_API const char* neraf_model_compute(const neraf_model* model) {
  if (!model) return "";
  switch (model->engine.bf16_kernel()) {
    case neraf::rt::Bf16Kernel::amx:
      return "bfloat16-amx";
    case neraf::rt::Bf16Kernel::avx512:
      return "bfloat16-avx512";
    case neraf::rt::Bf16Kernel::none:
      break;
  }
  return "float32";
}

NERAF_RT_API void neraf_model_free(neraf_model* model) { delete model; }

NERAF_RT_API neraf_status neraf_model_get_info(const neraf_model* model, neraf_model_info* out) {
  if (!model || !out)
    return fail(NERAF_ERR_INVALID_ARGUMENT, "neraf_model_get_info: model and out must not be NULL");
  *out = model->info;
  return NERAF_OK;
}

NERAF_RT_API neraf_status neraf_workspace_create(const neraf_model* model, neraf_workspace** out) {
  if (out) *out = nullptr;
  if (!model || !out)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                "neraf_workspace_create: model and out must not be NULL");
  return guarded("neraf_workspace_create", [&] {
    *out = new neraf_workspace(model);
    return NERAF_OK;
  });
}

NERAF_RT_API void neraf_workspace_free(neraf_workspace* workspace) { delete workspace; }

NERAF_RT_API neraf_status neraf_workspace_set_griffin_lim(neraf_workspace* workspace,
                                                          int iterations, uint64_t seed) {
  if (!workspace)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                "neraf_workspace_set_griffin_lim: workspace must not be NULL");
  if (iterations < 0 || iterations > 10000)
    return fail(NERAF_ERR_INVALID_ARGUMENT, "neraf_workspace_set_griffin_lim: iterations " +
                                                std::to_string(iterations) +
                                                " is outside [0, 10000]");
  workspace->ws.set_griffin_lim(iterations, seed);
  return NERAF_OK;
}

NERAF_RT_API neraf_status neraf_workspace_set_threads(neraf_workspace* workspace, int threads) {
  if (!workspace)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                "neraf_workspace_set_threads: workspace must not be NULL");
  if (threads < 0 || threads > 1024)
    return fail(NERAF_ERR_INVALID_ARGUMENT, "neraf_workspace_set_threads: threads " +
                                                std::to_string(threads) +
                                                " is outside [0, 1024] (0: automatic)");
  return guarded("neraf_workspace_set_threads", [&] {
    workspace->ws.set_threads(threads);
    return NERAF_OK;
  });
}

NERAF_RT_API neraf_status neraf_query_log_stft(const neraf_model* model, neraf_workspace* workspace,
                                               const neraf_pose* pose, unsigned flags, float* out,
                                               size_t capacity) {
  const neraf_status s = check_query("neraf_query_log_stft", model, workspace, pose, flags, out,
                                     capacity, model ? model->engine.log_stft_size() : 0);
  if (s != NERAF_OK) return s;
  return guarded("neraf_query_log_stft", [&] {
    model->engine.log_stft(*pose, workspace->ws, out);
    return NERAF_OK;
  });
}

NERAF_RT_API neraf_status neraf_query_rir(const neraf_model* model, neraf_workspace* workspace,
                                          const neraf_pose* pose, unsigned flags, float* out,
                                          size_t capacity) {
  const size_t needed = model ? size_t(model->info.channels) * size_t(model->info.rir_length) : 0;
  const neraf_status s =
      check_query("neraf_query_rir", model, workspace, pose, flags, out, capacity, needed);
  if (s != NERAF_OK) return s;
  return guarded("neraf_query_rir", [&] {
    model->engine.rir(*pose, workspace->ws, out);
    return NERAF_OK;
  });
}

}  // extern "C"

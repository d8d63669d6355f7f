#pragma once
// The C API's opaque types (neraf_rt.h declares them incomplete), for code inside neraf_rt that
// needs more than the public functions. A neraf_model is immutable after neraf_model_load; a
// neraf_workspace belongs to the model it was created for and to one thread at a time.
#include "neraf/neraf_rt.h"
#include "neraf/runtime/engine.h"

struct neraf_model {
  neraf_model(const neraf::rt::ModelData& m, const std::string& name, bool allow_bf16)
      : engine(m, name, allow_bf16) {
    info = engine.info();
  }
  neraf::rt::Engine engine;
  neraf_model_info info;
};

struct neraf_workspace {
  explicit neraf_workspace(const neraf_model* m) : model(m), ws(m->engine) {}
  const neraf_model* model;  // the model it was created for (queries check it)
  neraf::rt::Workspace ws;
};

#pragma once
// Minimal user-facing messages on stderr. Warnings never stop the work; errors are exceptions.
#include <cstdio>
#include <string>

namespace neraf {

inline void warn(const std::string& message) { std::fprintf(stderr, "warning: %s\n", message.c_str()); }
inline void info(const std::string& message) { std::fprintf(stderr, "%s\n", message.c_str()); }

}  // namespace neraf

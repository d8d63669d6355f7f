#pragma once
// One table of fields drives JSON save, load and printing of the config structs.
//
// A config struct lists its fields once, in a `visit` member:
//   template <class V> void visit(V& v) { v("hidden_dim", hidden_dim); v("grid", grid); }
// and `config_to_json(cfg)` / `config_from_json(json, cfg, where)` walk that list. Supported field
// types: bool, integers, double, std::string, enums with `to_string`/`parse_enum(tag, string)`
// overloads, structs with a `visit` member (or a free `visit_config(struct&, V&)`), and
// std::vector of any of these.
// Loading overlays onto `cfg` (keys that are missing keep their current value, so a partial file
// overrides a preset); unknown keys and wrong types are neraf::Error naming "<where>: <key>".
#include <nlohmann/json.hpp>

#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "neraf/nerf/hash_grid_kernel.h"
#include "neraf/util/error.h"

namespace neraf::nerf {

// HashGridConfig is owned by hash_grid_kernel.h; its field table lives here.
template <class V>
void visit_config(HashGridConfig& c, V& v) {
  v("num_levels", c.num_levels);
  v("features_per_level", c.features_per_level);
  v("log2_hashmap_size", c.log2_hashmap_size);
  v("base_resolution", c.base_resolution);
  v("max_resolution", c.max_resolution);
}

namespace config_detail {

struct ProbeVisitor {
  template <class U>
  void operator()(const char*, U&) {}
};
template <class T, class = void>
struct has_visit_member : std::false_type {};
template <class T>
struct has_visit_member<T, std::void_t<decltype(std::declval<T&>().visit(
                               std::declval<ProbeVisitor&>()))>> : std::true_type {};

template <class T>
struct is_vector : std::false_type {};
template <class T>
struct is_vector<std::vector<T>> : std::true_type {};

template <class T, class V>
void visit_struct(T& value, V& v) {
  if constexpr (has_visit_member<T>::value)
    value.visit(v);
  else
    visit_config(value, v);
}

struct Writer;
template <class T>
nlohmann::json write_value(const T& value);

struct Writer {
  nlohmann::json* out;
  template <class T>
  void operator()(const char* key, T& value) {
    (*out)[key] = write_value(value);
  }
};

template <class T>
nlohmann::json write_value(const T& value) {
  if constexpr (std::is_same_v<T, bool> || std::is_arithmetic_v<T> ||
                std::is_same_v<T, std::string>) {
    return value;
  } else if constexpr (std::is_enum_v<T>) {
    return to_string(value);
  } else if constexpr (is_vector<T>::value) {
    nlohmann::json arr = nlohmann::json::array();
    for (const auto& item : value) arr.push_back(write_value(item));
    return arr;
  } else {
    nlohmann::json obj = nlohmann::json::object();
    Writer w{&obj};
    visit_struct(const_cast<T&>(value), w);
    return obj;
  }
}

template <class T>
void read_value(const nlohmann::json& j, T& value, const std::string& where);

struct Reader {
  const nlohmann::json* in;
  std::string where;
  std::vector<std::string> seen;
  template <class T>
  void operator()(const char* key, T& value) {
    seen.emplace_back(key);
    auto it = in->find(key);
    if (it != in->end()) read_value(*it, value, where + "." + key);
  }
};

template <class T>
void read_value(const nlohmann::json& j, T& value, const std::string& where) {
  if constexpr (std::is_same_v<T, bool>) {
    require(j.is_boolean(), where + ": expected true or false");
    value = j.get<bool>();
  } else if constexpr (std::is_integral_v<T>) {
    using Limits = std::numeric_limits<T>;
    const std::string range = "an integer from " + std::to_string(Limits::min()) + " to " +
                              std::to_string(Limits::max()) + ", got " + j.dump();
    require(j.is_number_integer(), where + ": expected " + range);
    const bool fits = j.is_number_unsigned()
                          ? j.get<uint64_t>() <= static_cast<uint64_t>(Limits::max())
                          : j.get<int64_t>() >= static_cast<int64_t>(Limits::min()) &&
                                (static_cast<uint64_t>(Limits::max()) > uint64_t{INT64_MAX} ||
                                 j.get<int64_t>() <= static_cast<int64_t>(Limits::max()));
    require(fits, where + ": expected " + range);
    value = j.get<T>();
  } else if constexpr (std::is_floating_point_v<T>) {
    require(j.is_number(), where + ": expected a number");
    value = j.get<T>();
  } else if constexpr (std::is_same_v<T, std::string>) {
    require(j.is_string(), where + ": expected a string");
    value = j.get<std::string>();
  } else if constexpr (std::is_enum_v<T>) {
    require(j.is_string(), where + ": expected a string");
    value = parse_enum(T{}, j.get<std::string>(), where);
  } else if constexpr (is_vector<T>::value) {
    require(j.is_array(), where + ": expected an array");
    // Elements overlay onto the current elements where they exist (so a partial struct in an
    // array element keeps its defaults), default-constructed ones beyond.
    T out(j.size());
    for (size_t i = 0; i < j.size(); ++i) {
      if (i < value.size()) out[i] = value[i];
      read_value(j[i], out[i], where + "[" + std::to_string(i) + "]");
    }
    value = std::move(out);
  } else {
    require(j.is_object(), where + ": expected an object");
    Reader r{&j, where, {}};
    visit_struct(value, r);
    for (auto it = j.begin(); it != j.end(); ++it) {
      bool known = false;
      for (const auto& k : r.seen) known = known || k == it.key();
      require(known, where + "." + it.key() + ": unknown setting; remove it or check the spelling");
    }
  }
}

}  // namespace config_detail

template <class T>
nlohmann::json config_to_json(const T& config) {
  return config_detail::write_value(config);
}

// Overlays `j` onto `config`. `where` names the source in error messages (e.g. "RUN/config.json").
template <class T>
void config_from_json(const nlohmann::json& j, T& config, const std::string& where) {
  config_detail::read_value(j, config, where);
}

}  // namespace neraf::nerf

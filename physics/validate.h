// Physics refuses nonsense: each check returns an ok Status or one whose message names the field
// and the allowed range ("chain.links = 0: must be an integer in [1, 4096]"). Ranges come from the
// structs' reflect() lists (one source of truth with the scene file and the panel), plus the
// checks reflect cannot express (a zero direction vector).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <string>
#include <type_traits>
#include <utility>

#include "physics/physics_params.h"
#include "physics/reflect.h"
#include "physics/status.h"

namespace ponyhop {

// A reflect() visitor: every number finite and inside its [min, max], every enum a known value,
// through optional sections, lists and nested structs. Keeps the first error only.
struct RangeCheck {
  std::string prefix;
  std::string error;

  static std::string number(double x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", x);
    return buf;
  }

  template <class T>
  void operator()(const char* name, T& field, const FieldMeta& m) {
    visit(prefix + "." + name, field, m);
  }

 private:
  void check(const std::string& key, double value, const FieldMeta& m, bool integer) {
    if (!error.empty() || inRange(value, m)) return;
    error = key + " = " + number(value) + ": must be " + (integer ? "an integer" : "a finite number") + " in [" +
            number(m.min) + ", " + number(m.max) + "]" + (*m.unit ? std::string(" ") + m.unit : "") + " (" + m.help +
            ")";
  }

  template <class T>
  void visit(const std::string& key, T& field, const FieldMeta& m) {
    if constexpr (std::is_same_v<T, double>) {
      check(key, field, m, false);
    } else if constexpr (std::is_same_v<T, int>) {
      check(key, field, m, true);
    } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
      for (int i = 0; i < 3; ++i) check(key + "[" + std::to_string(i) + "]", field[i], m, false);
    } else if constexpr (std::is_enum_v<T>) {
      const auto i = static_cast<size_t>(field);
      if (error.empty() && i >= EnumNames<T>::names.size()) {
        error = key + ": unknown value " + std::to_string(i) + " (" + m.help + ")";
      }
    } else if constexpr (IsOptional<T>::value) {
      if (field) visit(key, *field, m);
    } else if constexpr (IsVector<T>::value) {
      for (size_t i = 0; i < field.size(); ++i) visit(key + "." + std::to_string(i), field[i], m);
    } else if constexpr (Reflectable<T>) {
      RangeCheck inner{key, ""};
      field.reflect(inner);
      if (error.empty()) error = inner.error;
    }
  }
};

// The first range error of a reflectable struct, or ok.
template <class P>
Status checkRanges(P p, const std::string& prefix) {
  RangeCheck v{prefix, ""};
  p.reflect(v);
  if (v.error.empty()) return {};
  return Status::error(std::move(v.error));
}

Status validate(const PhysicsParams& p, const std::string& prefix = "physics");

}  // namespace ponyhop

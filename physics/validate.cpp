#include "physics/validate.h"

#include <cmath>
#include <cstdio>
#include <type_traits>

namespace ponyhop {

namespace {

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

// A reflect() visitor: every number finite and inside its [min, max]; every enum a known value.
struct RangeCheck {
  std::string prefix;
  std::string error;

  void check(const std::string& name, double value, const FieldMeta& m, bool integer) {
    if (!error.empty()) return;
    if (std::isfinite(value) && value >= m.min && value <= m.max) return;
    error = prefix + "." + name + " = " + number(value) + ": must be " + (integer ? "an integer" : "a finite number") +
            " in [" + number(m.min) + ", " + number(m.max) + "]" + (*m.unit ? std::string(" ") + m.unit : "") +
            " (" + m.help + ")";
  }

  template <class T>
  void operator()(const char* name, T& field, const FieldMeta& m) {
    if constexpr (std::is_same_v<T, double>) {
      check(name, field, m, false);
    } else if constexpr (std::is_same_v<T, int>) {
      check(name, field, m, true);
    } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
      for (int i = 0; i < 3; ++i) check(std::string(name) + "[" + std::to_string(i) + "]", field[i], m, false);
    } else if constexpr (std::is_enum_v<T>) {
      const auto i = static_cast<size_t>(field);
      if (error.empty() && i >= EnumNames<T>::names.size()) {
        error = prefix + "." + name + ": unknown value " + std::to_string(i) + " (" + m.help + ")";
      }
    }
  }
};

template <class P>
std::string checkRanges(P p, const std::string& prefix) {
  RangeCheck v{prefix, ""};
  p.reflect(v);
  return v.error;
}

}  // namespace

std::string validate(const PhysicsParams& p, const std::string& prefix) {
  if (std::string e = checkRanges(p, prefix); !e.empty()) return e;
  if (!(p.dt > 0.0)) return prefix + ".dt must be positive";
  if (p.substeps < 1) return prefix + ".substeps must be at least 1";
  return "";
}

std::string validate(const ChainParams& p, const std::string& prefix) {
  if (std::string e = checkRanges(p, prefix); !e.empty()) return e;
  if (!(p.links >= 1)) return prefix + ".links must be at least 1";
  if (!(p.length > 0.0) || !(p.mass > 0.0) || !(p.radius > 0.0) || !(p.taper > 0.0)) {
    return prefix + ".length, .mass, .radius and .taper must be positive";
  }
  if (!(p.direction.norm() > 1e-9)) {
    return prefix + ".direction = (0, 0, 0): must be a non-zero vector (the chain's initial direction)";
  }
  return "";
}

std::string validate(const AnchorParams& p, const std::string& prefix) { return checkRanges(p, prefix); }

}  // namespace ponyhop

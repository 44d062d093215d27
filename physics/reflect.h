// Reflection of parameter structs: one list of fields serves the scene file, `--set key=value`,
// the tuning panel and the docs. A `...Params` struct lists its fields once:
//
//   struct ChainParams {
//     int links = 8;  // count
//     template <class V> void reflect(V& v) {
//       v("links", links, {.unit = "", .min = 1, .max = 4096, .help = "Number of links"});
//     }
//   };
//
// A visitor V is called as v(name, field, meta) for each field. Field types a visitor must
// handle: bool, int, double, std::string, Eigen::Vector3d, enums with EnumNames<E>,
// std::vector<T> and std::optional<T> of the above or of reflectable structs, and nested
// reflectable structs (anything else with a reflect(V&) member).
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string_view>
#include <type_traits>
#include <vector>

namespace ponyhop {

// How an edit of a field reaches a running simulation (the tuning panel, app/ui_sim.h). A
// section's setting holds for every field inside it unless the field says otherwise.
enum class Apply {
  Inherit,    // as the enclosing section (at the top level: KeepState)
  Live,       // nothing in the world depends on it: the next frame shows it
  KeepState,  // the world is rebuilt and the running state carried over
  Restart,    // it changes the bodies or the starting conditions: rebuilt at t = 0
};

struct FieldMeta {
  const char* unit = "";  // SI unit shown in the panel and the docs; "" when dimensionless
  double min = -std::numeric_limits<double>::infinity();  // allowed range (inclusive)
  double max = std::numeric_limits<double>::infinity();
  const char* help = "";  // one sentence: the panel's tooltip and the docs' description
  bool log = false;       // the value spans decades: logarithmic slider in the panel
  Apply apply = Apply::Inherit;
  // The panel slider's range where the allowed range is far wider than anything useful to drag
  // through (a typed value reaches the whole allowed range). NaN: the allowed range.
  double soft_min = std::numeric_limits<double>::quiet_NaN();
  double soft_max = std::numeric_limits<double>::quiet_NaN();
};

// The one range test of every number a file, `--set`, the panel or a program gives a field:
// finite and within [min, max].
inline bool inRange(double x, const FieldMeta& meta) { return std::isfinite(x) && x >= meta.min && x <= meta.max; }

// Names of an enum's values in the scene file, in the enum's order. Specialize per enum:
//   template <> struct EnumNames<Integrator> {
//     static constexpr std::array<std::string_view, 2> names{"symplectic_euler", "rk4"};
//   };
template <class E>
struct EnumNames;

template <class E>
constexpr std::string_view enumName(E e) {
  const auto i = static_cast<size_t>(e);
  return i < EnumNames<E>::names.size() ? EnumNames<E>::names[i] : std::string_view("(invalid)");
}

// True when `name` is one of E's names; writes the value.
template <class E>
constexpr bool enumFromName(std::string_view name, E& out) {
  for (size_t i = 0; i < EnumNames<E>::names.size(); ++i) {
    if (EnumNames<E>::names[i] == name) {
      out = static_cast<E>(i);
      return true;
    }
  }
  return false;
}

// Type tests for visitors that walk the field types listed above.
template <class T>
struct IsOptional : std::false_type {};
template <class T>
struct IsOptional<std::optional<T>> : std::true_type {};
template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};

// Any struct with a reflect(V&) member: a visitor descends into it as a group of fields.
struct ReflectProbe {
  template <class T>
  void operator()(const char*, T&, const FieldMeta&) {}
};
template <class T>
concept Reflectable = requires(T& t, ReflectProbe& v) {
  t.reflect(v);
};

// The metadata of the field at a dotted key ("chain.links", "head.animation.clip") below a
// reflectable struct, with `apply` resolved through the enclosing sections. Lists are leaves
// ("hopper.script"). False when there is no such field.
class FieldFinder {
 public:
  FieldFinder(std::string_view key, Apply inherited) : key_(key), inherited_(inherited) {}

  template <class T>
  void operator()(const char* name, T& field, const FieldMeta& meta) {
    if (found) return;
    const size_t dot = key_.find('.');
    if (key_.substr(0, dot) != name) return;
    const Apply apply = meta.apply == Apply::Inherit ? inherited_ : meta.apply;
    if (dot == std::string_view::npos) {
      found = true;
      result = meta;
      result.apply = apply;
      return;
    }
    FieldFinder inner(key_.substr(dot + 1), apply);
    if constexpr (IsOptional<T>::value) {
      if constexpr (Reflectable<typename T::value_type>) {
        typename T::value_type probe{};
        probe.reflect(inner);
      }
    } else if constexpr (Reflectable<T>) {
      field.reflect(inner);
    }
    found = inner.found;
    result = inner.result;
  }

  bool found = false;
  FieldMeta result;

 private:
  std::string_view key_;
  Apply inherited_;
};

template <class Root>
bool findField(Root& root, std::string_view key, FieldMeta& out) {
  FieldFinder f(key, Apply::KeepState);
  root.reflect(f);
  if (f.found) out = f.result;
  return f.found;
}

}  // namespace ponyhop

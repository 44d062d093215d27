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
#include <limits>
#include <optional>
#include <string_view>
#include <type_traits>
#include <vector>

namespace ponyhop {

struct FieldMeta {
  const char* unit = "";  // SI unit shown in the panel and the docs; "" when dimensionless
  double min = -std::numeric_limits<double>::infinity();  // allowed range (inclusive)
  double max = std::numeric_limits<double>::infinity();
  const char* help = "";  // one sentence: the panel's tooltip and the docs' description
  bool log = false;       // the value spans decades: logarithmic slider in the panel
};

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
concept Reflectable = requires(T& t, ReflectProbe& v) { t.reflect(v); };

}  // namespace ponyhop

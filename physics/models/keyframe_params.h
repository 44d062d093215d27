// Keyframes of a kinematic body (the head): poses at times. The curve through them is built by
// physics/models/keyframes.h (C2 in position and orientation, so accelerations are continuous).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "physics/reflect.h"

namespace ponyhop {

struct Keyframe {
  double t = 0.0;                           // s
  Eigen::Vector3d position{0.0, 0.0, 0.0};  // m, world frame
  Eigen::Vector3d rotation{0.0, 0.0, 0.0};  // deg, Euler angles about x, y, z: R = Rz Ry Rx

  template <class V>
  void reflect(V& v) {
    v("t", t, {.unit = "s", .min = 0, .max = 1e6, .help = "Time of the key"});
    v("position", position, {.unit = "m", .min = -1e3, .max = 1e3, .help = "Position"});
    v("rotation", rotation,
      {.unit = "deg", .min = -1e5, .max = 1e5, .help = "Euler angles about x, y, z (R = Rz Ry Rx)"});
  }
};

enum class LoopMode { Clamp, Loop };
template <>
struct EnumNames<LoopMode> {
  static constexpr std::array<std::string_view, 2> names{"clamp", "loop"};
};

struct AnimationParams {
  // A clip in assets/animations/ by name (nod, shake, ...), a path to a clip file, "mesh" for the
  // animation inside the head's mesh file (imported through assimp), or "" for `keys` below.
  std::string clip = "";
  std::vector<Keyframe> keys;  // inline keys, used when clip is ""
  LoopMode mode = LoopMode::Loop;
  double speed = 1.0;      // playback rate (2: twice as fast)
  double amplitude = 1.0;  // scales each key's offset from the first key

  template <class V>
  void reflect(V& v) {
    v("clip", clip, {.help = "Clip name in assets/animations/, a clip file, \"mesh\", or \"\" for keys"});
    v("keys", keys, {.help = "Inline keyframes (when clip is empty)"});
    v("mode", mode, {.help = "After the last key: clamp (hold) or loop"});
    v("speed", speed, {.min = 0.01, .max = 100, .help = "Playback rate", .log = true});
    v("amplitude", amplitude, {.min = 0, .max = 10, .help = "Scales the motion away from the first key"});
  }
};

}  // namespace ponyhop

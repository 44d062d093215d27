// Keyframes from a mesh file's animation (glTF, FBX, Collada, ... through assimp), as pose samples
// for physics/models/keyframes.h (docs/ANIMATION.md).
//
// assimp 5.2.5 keeps animation keys as samples only (glTF cubic-spline tangents are dropped and
// the interpolation mode is not recorded), so they are treated as samples and the C2 track of
// physics/models/keyframes.h interpolates them. A node's position and rotation channels may be keyed at
// different times: both are resampled onto the union of their key times (linear for position,
// slerp for rotation, holding the first/last key outside a channel's range). Scale keys are
// ignored (the head is rigid).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "physics/models/keyframes.h"

namespace ponyhop {

struct AnimationImportOptions {
  // Convert a y-up file (glTF is y up by specification) to ponyhop's z-up world: positions and
  // rotations are conjugated by C = +90 degrees about x, which maps (x, y, z) to (x, -z, y) (file
  // +y -> world +z, file +z (a glTF face's forward) -> world -y (ponyhop's face direction)):
  //   p_world = C p,   q_world = C q C^-1.
  // This is the same fix the scene applies to a y-up mesh (HeadParams::up_axis = y), so pass
  // `head.up_axis == UpAxis::Y`. false: the file's coordinates are used as they are.
  bool y_up_to_z_up = false;
  std::string animation;  // animation name; "" = the file's first animation
  std::string node;       // animated node's name; "" = the animation's first channel
};

struct ImportedAnimation {
  std::vector<PoseSample> samples;  // time (s, from the file's key times), pose of the node
  std::string animation_name;
  std::string node_name;
  double ticks_per_second = 0;  // as used (the file's value, or 25 when the file says 0)
  int position_keys = 0;        // keys in the file's channels, before merging
  int rotation_keys = 0;
};

// Reads `path` and returns its animation's samples. On failure: nullopt, and *error (when not
// null) names the file and what is wrong (unreadable, no animation, no such node, no keys).
std::optional<ImportedAnimation> importAnimation(const std::string& path, const AnimationImportOptions& options,
                                                 std::string* error = nullptr);

// importAnimation + KeyframeTrack::fromSamples, errors prefixed with the file name.
std::optional<KeyframeTrack> importAnimationTrack(const std::string& path, const AnimationImportOptions& options,
                                                  const TrackOptions& track, std::string* error = nullptr);

}  // namespace ponyhop

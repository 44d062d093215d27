// libFuzzer target: keyframe clip files (engine/scene_io's clip reader, then the keyframe track
// that the head plays). Every input ends in a track, a message, or a InputError.
#include <cstddef>
#include <cstdint>
#include <string>

#include "physics/models/keyframes.h"
#include "sim/scene_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const ponyhop::AnimationParams clip = ponyhop::parseClipText(text, "fuzz_clip.json");
    ponyhop::KeyframeTrack track;
    const ponyhop::Status s = ponyhop::KeyframeTrack::fromKeyframes(clip.keys, ponyhop::trackOptions(clip), track);
    if (s.ok()) {
      for (double t : {0.0, 0.37, 1.0, 12.5}) (void)track.evaluate(t);
    } else if (s.message().empty()) {
      __builtin_trap();  // a refusal must say why
    }
  } catch (const ponyhop::InputError&) {
  }
  return 0;
}

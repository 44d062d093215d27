// libFuzzer target: the scene reader with --set overrides (engine/scene_io). Input: scene JSON,
// then optionally a NUL byte and up to 4 lines of `key=value` overrides. Every input must end in
// a Scene or a InputError; a scene that was read must write and read back to the same JSON.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/scene_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const size_t nul = input.find('\0');
  const std::string text = input.substr(0, nul);
  std::vector<ponyhop::Override> overrides;
  try {
    if (nul != std::string::npos) {
      size_t at = nul + 1;
      while (at <= input.size() && overrides.size() < 4) {
        const size_t end = std::min(input.find('\n', at), input.size());
        overrides.push_back(ponyhop::parseOverride(input.substr(at, end - at)));
        at = end + 1;
      }
    }
    const ponyhop::Scene scene = ponyhop::parseSceneText(text, "fuzz.json", overrides);
    const nlohmann::json written = ponyhop::sceneToJson(scene);
    const ponyhop::Scene again = ponyhop::parseSceneText(written.dump(), "fuzz-written.json");
    if (ponyhop::sceneToJson(again) != written) __builtin_trap();  // the writer and reader disagree
  } catch (const ponyhop::InputError&) {
    // a refusal with a message: the expected outcome for most inputs
  }
  return 0;
}

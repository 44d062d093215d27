// Rendering a part of a sequence (a render farm's chunk): `ponyhop render --range A:B` and
// `--resume`. A chunk replays the simulation (and the follow camera) from t = 0 and renders only
// its own frames, so its PNGs are byte-identical to the same frames of a full run; frames are
// written straight into the output folder, each atomically, and the others are left alone.
#pragma once

#include <string>

namespace ponyhop {

class RenderSession;

struct FrameRange {
  int first = 0;  // inclusive
  int last = 0;   // inclusive
  bool contains(int i) const { return i >= first && i <= last; }
};

// "A:B" (inclusive), "A:" (to the end) or "A" (one frame), within [0, frames). Throws InputError
// naming --range and what is allowed.
FrameRange parseFrameRange(const std::string& text, int frames);

// Renders the frames of `range` into `out` (created when missing) with the session fresh at
// t = 0; with `resume`, frames already in `out` whole are not rendered again. Prints progress and a
// summary on stderr. 0 on success, 1 when the simulation stopped or a write failed (frames
// already written stay: a later --resume goes on from there).
int renderChunk(RenderSession& session, double fps, const std::string& out, FrameRange range, bool resume);

// True when `path` is a PNG written whole: the signature at the start and the IEND chunk at the end.
bool pngIsWhole(const std::string& path);

}  // namespace ponyhop

// Drawing a Sim (sim/sim.h): the head's mesh, the chain's links, the hoppers, with the colours
// and materials of the scene's drawing fields. The physics knows none of this.
#pragma once

#include <vector>

#include "engine/renderer.h"
#include "sim/sim.h"

namespace ponyhop {

class SceneDraw {
 public:
  // GL: uploads the sim's meshes (the head) into `renderer`, once per renderer; the handles are
  // released by release() or with the renderer.
  void upload(const Sim& sim, Renderer& renderer);
  void release();
  bool uploaded() const { return renderer_ != nullptr; }
  // Draws the sim's current state with its scene's look (needs upload() first for the head).
  void draw(const Sim& sim, Renderer& renderer) const;

 private:
  Renderer* renderer_ = nullptr;
  MeshHandle head_;
};

}  // namespace ponyhop

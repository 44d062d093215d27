// Drawing a Sim (sim/sim.h): the head's mesh, the chain's links, the hoppers, with the colours
// and materials of the scene's drawing fields. The physics knows none of this.
#pragma once

#include <vector>

#include "engine/hair.h"
#include "engine/renderer.h"
#include "sim/sim.h"

namespace ponyhop {

class SceneDraw {
 public:
  // GL: uploads the sim's meshes (the head) into `renderer`, once per renderer; the handles are
  // released by release() or with the renderer.
  void upload(const Sim& sim, Renderer& renderer);
  void release();
  // Draws the sim's current state with its scene's look (needs upload() first for the head).
  void draw(const Sim& sim, Renderer& renderer) const;
  // The same with the drawing fields of the chain taken from `look` (the panel's applied scene:
  // hair knobs change live, without rebuilding the sim).
  void draw(const Sim& sim, Renderer& renderer, const Scene& look, unsigned hide = 0) const;
  // Parts of a scene that draw() can leave out (bits; `ponyhop snapshot` measures how much of the
  // picture a shot's subject covers by drawing it once with and once without).
  enum Part : unsigned { kHead = 1, kChain = 2, kHopper = 4 };
  // s: render.goals draws a goal's marker bright while the time is this close to the goal's.
  static constexpr double kGoalNear = 0.25;
  // The parts `sim` has.
  static unsigned parts(const Sim& sim);
  // Draft quality draws fewer hair strands (HairParams::strands_draft).
  void setDraft(bool draft) { draft_ = draft; }
  // The chain dressed as hair, as draw() hands it to the renderer.
  HairMesh chainHair(const Sim& sim, const Chain& chain, const ChainSection& look) const;

 private:
  void drawChain(const Sim& sim, const Chain& chain, const ChainSection& look, Renderer& renderer) const;
  // render.colliders: the collision shapes as wireframes and the contacts as normals, on top.
  void drawColliders(const Sim& sim, Renderer& renderer) const;
  // render.active_joints: an orange ring about every chain joint that moved in the last step.
  void drawActiveJoints(const Sim& sim, Renderer& renderer) const;
  // render.goals: each of `drawing`'s goals as a wire sphere and cross at its target (docs/GOALS.md).
  void drawGoals(const Sim& sim, const Scene& drawing, Renderer& renderer) const;
  bool draft_ = false;
  Renderer* renderer_ = nullptr;
  MeshHandle head_;
};

}  // namespace ponyhop

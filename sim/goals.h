// Goals: where a point of the ponytail (or of the hopper) must be at a time (docs/GOALS.md). The
// scene's `goals` list; `ponyhop solve` finds the gentlest guide torques that meet them
// (sim/goal_solve.h) and writes them into the scene's `guide` section.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "physics/reflect.h"

namespace ponyhop {

// The frame a goal's position is given in: the world, or the head's body frame (the goal moves
// with the head).
enum class GoalFrame { World, Head };
template <>
struct EnumNames<GoalFrame> {
  static constexpr std::array<std::string_view, 2> names{"world", "head"};
};

struct Goal {
  double t = 0.0;  // s
  // "tip" (the chain's free end), "link:K" (the far end of link K, 0 = the root link), "toe" (the
  // first hopper's toe), "body" (the first hopper's body centre).
  std::string point = "tip";
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // m, in `frame`
  GoalFrame frame = GoalFrame::World;
  double tolerance = 0.005;  // m: met when the point is this close
  double weight = 1.0;       // relative importance when goals cannot all be met

  template <class V>
  void reflect(V& v) {
    v("t", t, {.unit = "s", .min = 0, .max = 1e6, .help = "Time at which the point must be there"});
    v("point", point, {.help = "Which point: tip, link:K (far end of link K), toe or body (the first hopper)"});
    v("position", position, {.unit = "m", .min = -1e4, .max = 1e4, .help = "Where the point must be, in `frame`"});
    v("frame", frame, {.help = "world, or head (the head's body frame: the goal moves with the head)"});
    v("tolerance", tolerance, {.unit = "m", .min = 1e-6, .max = 10, .help = "Met when this close", .log = true});
    v("weight", weight,
      {.min = 1e-6, .max = 1e6, .help = "Relative importance when not every goal can be met", .log = true});
  }
};

// What a goal's point names: the chain's tip or the far end of link `link`, or a hopper point.
struct GoalPoint {
  enum class Kind { Tip, Link, Toe, Body } kind = Kind::Tip;
  int link = -1;  // Link only
};
// Parses "tip", "link:K", "toe", "body"; false (with `why`) for anything else.
bool parseGoalPoint(const std::string& text, GoalPoint& out, std::string* why = nullptr);

struct Scene;
class Sim;
// Where goal `goal`'s point is in `sim` now (world, m): the chain's tip or a link's far end, the
// first hopper's toe or body centre; false when the sim has no such part or the point is not valid.
bool goalPointNow(const Sim& sim, const Goal& goal, Eigen::Vector3d& out);
// Where the goal wants it now (world, m): its position, carried by the head's pose for frame "head".
Eigen::Vector3d goalTargetNow(const Sim& sim, const Goal& goal);
// The scene's goals and guide against what the scene has (a link of the chain, a hopper, a head
// for frame "head", the guide's joints): one message per problem, appended to `errors`.
void checkGoals(const Scene& scene, std::vector<std::string>& errors);

}  // namespace ponyhop

#include "sim/goals.h"

#include <cstdlib>

#include "sim/scene.h"
#include "sim/sim.h"

namespace ponyhop {

bool parseGoalPoint(const std::string& text, GoalPoint& out, std::string* why) {
  const auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  if (text == "tip") {
    out = {GoalPoint::Kind::Tip, -1};
  } else if (text == "toe") {
    out = {GoalPoint::Kind::Toe, -1};
  } else if (text == "body") {
    out = {GoalPoint::Kind::Body, -1};
  } else if (text.rfind("link:", 0) == 0) {
    const std::string k = text.substr(5);
    char* end = nullptr;
    const long v = std::strtol(k.c_str(), &end, 10);
    if (k.empty() || *end != '\0' || v < 0 || v > 4095) return fail("link:K needs a link number K >= 0, e.g. link:3");
    out = {GoalPoint::Kind::Link, int(v)};
  } else {
    return fail("must be tip, link:K, toe or body");
  }
  return true;
}

void checkGoals(const Scene& scene, std::vector<std::string>& errors) {
  const bool has_hopper = scene.hopper || !scene.hoppers.empty();
  for (size_t i = 0; i < scene.goals.size(); ++i) {
    const Goal& g = scene.goals[i];
    const std::string key = "goals." + std::to_string(i) + ".";
    GoalPoint p;
    std::string why;
    if (!parseGoalPoint(g.point, p, &why)) {
      errors.push_back(key + "point: \"" + g.point.substr(0, 80) + "\" " + why);
      continue;
    }
    if ((p.kind == GoalPoint::Kind::Tip || p.kind == GoalPoint::Kind::Link) && !scene.chain) {
      errors.push_back(key + "point: \"" + g.point + "\" needs a chain section");
    } else if (p.kind == GoalPoint::Kind::Link && p.link >= scene.chain->links) {
      errors.push_back(key + "point: \"" + g.point + "\": the chain has links 0.." +
                       std::to_string(scene.chain->links - 1));
    }
    if ((p.kind == GoalPoint::Kind::Toe || p.kind == GoalPoint::Kind::Body) && !has_hopper) {
      errors.push_back(key + "point: \"" + g.point + "\" needs a hopper section");
    }
    if (g.frame == GoalFrame::Head && !scene.head) errors.push_back(key + "frame: \"head\" needs a head section");
  }
  if (scene.guide) {
    if (!scene.chain && !has_hopper) {
      errors.push_back(
          "guide: needs a chain section (its knots turn the chain's joints) or a hopper section (its "
          "script commands the hopper)");
    } else if (scene.guide->knots.empty()) {
      // nothing to check against a chain
    } else if (!scene.chain) {
      errors.push_back("guide.knots: needs a chain section (the torques act at the chain's joints)");
    } else if (Status s = validate(*scene.guide, scene.chain->links); !s.ok()) {
      errors.push_back(s.message());
    }
    const std::vector<HopperCommandKey>& script = scene.guide->script;
    if (!script.empty() && !has_hopper) errors.push_back("guide.script: needs a hopper section (it is its commands)");
    for (size_t i = 1; i < script.size(); ++i) {
      if (script[i].t <= script[i - 1].t) {
        errors.push_back("guide.script." + std::to_string(i) + ".t = " + std::to_string(script[i].t) +
                         " s: keys must be in increasing time order (the previous key is at " +
                         std::to_string(script[i - 1].t) + " s)");
        break;
      }
    }
  }
}

bool goalPointNow(const Sim& sim, const Goal& goal, Eigen::Vector3d& out) {
  GoalPoint p;
  if (!parseGoalPoint(goal.point, p)) return false;
  const World& w = sim.world();
  switch (p.kind) {
    case GoalPoint::Kind::Tip:
      if (!sim.chain()) return false;
      out = sim.chain()->tip(w);
      return true;
    case GoalPoint::Kind::Link:
      if (!sim.chain() || p.link >= int(sim.chain()->links.size())) return false;
      out = sim.chain()->bottom(w, p.link);
      return true;
    case GoalPoint::Kind::Toe:
      if (!sim.hopper()) return false;
      out = sim.hopper()->footPoint(w);
      return true;
    case GoalPoint::Kind::Body:
      if (!sim.hopper()) return false;
      out = w.body(sim.hopper()->model().body).x;
      return true;
  }
  return false;
}

Eigen::Vector3d goalTargetNow(const Sim& sim, const Goal& goal) {
  if (goal.frame == GoalFrame::Head && sim.headBody() >= 0)
    return sim.world().body(sim.headBody()).pointToWorld(goal.position);
  return goal.position;
}

}  // namespace ponyhop

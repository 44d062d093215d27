#include "app/pose_sampling.h"

#include <cmath>
#include <utility>

namespace ponyhop {

PoseSampler::PoseSampler(Sim& sim) : rt_(sim) {
  capturePoses(sim.time(), sim.world().bodies(), cur_);
  prev_ = cur_;
}

bool PoseSampler::stepOnce() {
  if (!rt_.step()) return false;
  std::swap(prev_, cur_);  // the older frame's storage takes the new poses: nothing allocated per step
  capturePoses(rt_.time(), rt_.world().bodies(), cur_);
  return true;
}

bool PoseSampler::at(double t, PoseFrame& out) {
  const double eps = 1e-9 * rt_.scene().physics.dt;
  while (cur_.t < t - eps) {
    if (!stepOnce()) return false;
  }
  if (std::abs(cur_.t - t) <= eps || t <= prev_.t) {
    out = std::abs(cur_.t - t) <= eps ? cur_ : prev_;
    out.t = t;
    return true;
  }
  out = interpolatePoses(prev_, cur_, t);
  return true;
}

bool PoseSampler::nextStep(PoseFrame& out) {
  if (!stepOnce()) return false;
  out = cur_;
  return true;
}

std::vector<std::string> bodyIds(const World& world) {
  std::vector<std::string> ids;
  for (int i = 0; i < world.bodyCount(); ++i) {
    std::string s = world.body(i).name.empty() ? "body " + std::to_string(i) : world.body(i).name;
    for (char& c : s)
      if (c == ' ' || c == ',' || c == '"') c = '_';
    ids.push_back(s);
  }
  return ids;
}

}  // namespace ponyhop

// The integrators behind one interface, as the multiplier solvers are behind ConstraintSolver:
// World asks which method params.integrator names once, when it is built
// (World::makeIntegratorScheme), and from then on calls the scheme (as MuJoCo's mj_step
// dispatches once). Each scheme owns its stages of a substep and says what step control it
// needs; the arithmetic of each method stays in its own file (symplectic_euler.h, rk4.h,
// rattle.h, implicit_euler.h), which knows nothing of World.
//
//   method            order  may fail  stability limit (h rho)  count from both ends of dt
//   symplectic Euler  1      no        2                        no
//   RK4               4      no        2.83                     no
//   RATTLE            2      yes       2                        yes
//   implicit Euler    1      yes       none (not watched)       no
//
// The schemes are World's nested classes: their stages are World's private ones.
#pragma once

#include <cmath>

#include "physics/world.h"

namespace ponyhop {

// The finite-value checks of World's stages and of the schemes' integrate stages.
namespace checks {

constexpr double kHuge = 1e10;  // |x|, |v|, |w| beyond this: the run has diverged (cf. mj_checkPos)

// Per entry with std::isfinite and |x| < kHuge (NaN fails both): Eigen's allFinite (x - x == x -
// x) and lpNorm were left as calls in the per-body checks.
template <class V>
bool finite(const V& v) {
  for (int i = 0; i < v.size(); ++i)
    if (!std::isfinite(v(i))) return false;
  return true;
}
inline bool finiteAndBounded(const Eigen::Vector3d& v) {
  return std::abs(v(0)) < kHuge && std::abs(v(1)) < kHuge && std::abs(v(2)) < kHuge;
}

}  // namespace checks

class World::IntegratorScheme {
 public:
  virtual ~IntegratorScheme() = default;

  virtual Integrator kind() const = 0;
  // The order of the method (step doubling's error estimate, the tolerance mode's growth).
  virtual int order() const = 0;
  // A step can fail and ask to be taken as two halves (RATTLE's position solve, implicit Euler's
  // Newton iteration): substep() keeps a snapshot to undo it.
  virtual bool mayFail() const = 0;
  // The largest h rho the stability monitor lets pass (docs/STABILITY.md); 0: the method is
  // stable for any step and is not watched.
  virtual double stabilityLimit() const = 0;
  // The monitor reads the bodies in place (the integrate stage steps them in place) rather than
  // a gathered copy.
  virtual bool observesInPlace() const { return false; }
  // step() with max_step_rotation: the count must hold at the end of dt as well, or the dt is
  // taken again with the end's count (a reversible method keeps its bounded energy error only
  // with time-symmetric steps; docs/STABILITY.md).
  virtual bool symmetricCount() const { return false; }

  // Stages 1-6 of one substep of length h, in the method's order (not featherstone, which
  // replaces them by one joint-space step).
  virtual void takeStep(World& w, double h) = 0;
  // The integrate stage: t += h. `gathered`: watchStability() left the state and accelerations
  // in w's scratch.
  virtual void integrate(World& w, double h, bool gathered) = 0;
};

}  // namespace ponyhop

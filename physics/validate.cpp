#include "physics/validate.h"

namespace ponyhop {

Status validate(const PhysicsParams& p, const std::string& prefix) {
  if (Status s = checkRanges(p, prefix); !s.ok()) return s;
  if (!(p.dt > 0.0)) return Status::error(prefix + ".dt must be positive");
  if (p.substeps < 1) return Status::error(prefix + ".substeps must be at least 1");
  if (p.solver == SolverKind::Featherstone && p.integrator != Integrator::RK4 &&
      p.integrator != Integrator::SymplecticEuler) {
    return Status::error(prefix + ".integrator = '" + std::string(enumName(p.integrator)) +
                         "': solver 'featherstone' integrates in joint space with rk4 or symplectic_euler ('" +
                         std::string(enumName(p.integrator)) + "' belongs to the multiplier formulation)");
  }
  if (p.stabilization == Stabilization::Velocity &&
      (p.integrator != Integrator::SymplecticEuler || p.solver == SolverKind::Featherstone)) {
    return Status::error(prefix +
                         ".stabilization = 'velocity': joints at velocity level are symplectic Euler's in "
                         "the multiplier solvers (integrator 'symplectic_euler', solver 'dense' or 'tree'; "
                         "here integrator '" +
                         std::string(enumName(p.integrator)) + "', solver '" + std::string(enumName(p.solver)) + "')");
  }
  if ((p.adaptive_joints > 0 || p.adaptive_tolerance > 0.0) && p.solver != SolverKind::Featherstone) {
    return Status::error(prefix + (p.adaptive_joints > 0 ? ".adaptive_joints" : ".adaptive_tolerance") +
                         ": adaptive dynamics runs on solver 'featherstone' only (physics.solver = '" +
                         std::string(enumName(p.solver)) + "'; the multiplier solvers have no rigid joints)");
  }
  return {};
}

}  // namespace ponyhop

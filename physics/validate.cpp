#include "physics/validate.h"

namespace ponyhop {

std::string validate(const PhysicsParams& p, const std::string& prefix) {
  if (std::string e = checkRanges(p, prefix); !e.empty()) return e;
  if (!(p.dt > 0.0)) return prefix + ".dt must be positive";
  if (p.substeps < 1) return prefix + ".substeps must be at least 1";
  if (p.solver == SolverKind::Featherstone && p.integrator != Integrator::RK4 &&
      p.integrator != Integrator::SymplecticEuler) {
    return prefix + ".integrator = '" + std::string(enumName(p.integrator)) +
           "': solver 'featherstone' integrates in joint space with rk4 or symplectic_euler ('" +
           std::string(enumName(p.integrator)) + "' belongs to the multiplier formulation)";
  }
  return "";
}

}  // namespace ponyhop
